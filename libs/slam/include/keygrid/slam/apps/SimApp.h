#pragma once
/** \file SimApp.h
 * keygrid-sim: renders a synthetic RGB-D sequence from a scene INI (config/sim/NAME.ini) into
 * DIR/sequence.rawlog, DIR/groundtruth.txt, DIR/tum/ and ground-truth occupancy
 * (see keygrid/sim/SequenceWriter.h and doc/simulator.md).
 */
namespace keygrid::slam
{
class SimApp
{
   public:
	int run(int argc, const char* const* argv);
};

}  // namespace keygrid::slam
