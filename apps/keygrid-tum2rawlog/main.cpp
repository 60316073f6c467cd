// keygrid-tum2rawlog: TUM RGB-D folder -> MRPT rawlog. Logic: keygrid::slam::Tum2RawlogApp.
#include <keygrid/slam/apps/Tum2RawlogApp.h>

int main(int argc, char** argv) { return keygrid::slam::Tum2RawlogApp().run(argc, argv); }
