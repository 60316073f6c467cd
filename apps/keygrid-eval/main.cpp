// keygrid-eval: ATE / RPE of a TUM trajectory against ground truth. Logic: keygrid::slam::EvalApp.
#include <keygrid/slam/apps/EvalApp.h>

int main(int argc, char** argv) { return keygrid::slam::EvalApp().run(argc, argv); }
