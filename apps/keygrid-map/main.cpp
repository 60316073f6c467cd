// keygrid-map: inspects session files (info, check). Logic: keygrid::slam::MapApp.
#include <keygrid/slam/apps/MapApp.h>

int main(int argc, char** argv) { return keygrid::slam::MapApp().run(argc, argv); }
