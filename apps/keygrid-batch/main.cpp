// keygrid-batch: datasets x configurations as parallel keygrid-slam runs. Logic: keygrid::slam::BatchApp.
#include <keygrid/slam/apps/BatchApp.h>

int main(int argc, char** argv) { return keygrid::slam::BatchApp().run(argc, argv); }
