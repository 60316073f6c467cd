// keygrid-sim: synthetic RGB-D sequences with exact ground truth. Logic: keygrid::slam::SimApp.
#include <keygrid/slam/apps/SimApp.h>

int main(int argc, char** argv) { return keygrid::slam::SimApp().run(argc, argv); }
