// keygrid-slam: RGB-D SLAM on a rawlog or TUM folder. Logic: keygrid::slam::SlamApp.
#include <keygrid/slam/apps/SlamApp.h>

int main(int argc, char** argv) { return keygrid::slam::SlamApp().run(argc, argv); }
