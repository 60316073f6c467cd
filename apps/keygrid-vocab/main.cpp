// keygrid-vocab: trains / describes vocabulary trees for loop closure. Logic: keygrid::slam::VocabApp.
#include <keygrid/slam/apps/VocabApp.h>

int main(int argc, char** argv) { return keygrid::slam::VocabApp().run(argc, argv); }
