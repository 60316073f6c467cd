#pragma once
/** \file Tum2RawlogApp.h
 * keygrid-tum2rawlog: TUM RGB-D folder -> MRPT rawlog of CObservation3DRangeScan, with depth
 * kept at full precision (rangeUnits = 1/5000 m, the raw PNG values copied unchanged).
 */
#include <string>

namespace keygrid::slam
{
class Tum2RawlogApp
{
   public:
	/** Parses argv; returns the process exit code. Prints progress and a summary. */
	int run(int argc, const char* const* argv);
};

struct Tum2RawlogOptions
{
	std::string input, output;
	/** Preset name or INI file; empty: guessed from the folder (see TumSequence::guessCamera) */
	std::string camera;
	double maxAssociationDt{0.02};
	bool externalImages{false};
	bool quiet{false};
};

/** The conversion itself, callable from tests. Returns the number of observations written. */
std::size_t convertTumToRawlog(const Tum2RawlogOptions& opts);

}  // namespace keygrid::slam
