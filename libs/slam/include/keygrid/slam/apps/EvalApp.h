#pragma once
/** \file EvalApp.h
 * keygrid-eval: ATE (SE(3) or Sim(3) aligned) and RPE of a TUM trajectory against ground truth.
 */
namespace keygrid::slam
{
class EvalApp
{
   public:
	int run(int argc, const char* const* argv);
};

}  // namespace keygrid::slam
