#pragma once
// Small scenes for the simulator tests: 160x120 images so that every test runs in milliseconds.
#include <keygrid/sim/Scene.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <string>

namespace keygrid::test
{
/** A [camera] section for a 160 x 120 pinhole camera (Kinect field of view). */
inline std::string tinyCameraIni()
{
	return "[camera]\nwidth = 160\nheight = 120\nfx = 131.25\nfy = 131.25\ncx = 79.5\ncy = 59.5\n";
}

/** Parses a scene from INI text. */
inline sim::Scene sceneFromString(const std::string& ini, unsigned frames = 0)
{
	mrpt::config::CConfigFileMemory cfg(ini);
	return sim::Scene::loadFromConfig(cfg, "test-scene", frames);
}

/** Static camera at (0, 0, 1) looking along +x at a textured wall x = wallX, plus optional
 * extra INI text (objects, sensor keys...). */
inline std::string wallSceneIni(
	double wallX, const std::string& sensor, const std::string& extra = "")
{
	const std::string x = std::to_string(wallX);
	return "[scene]\nname = wall\nseed = 5\nframes = 3\n" + tinyCameraIni() + "[sensor]\n" +
		   sensor +
		   "\n[trajectory]\nwp_00 = 0 0 1  5 0 1\n"
		   "[object.wall]\ntype = quad\ncorner = " +
		   x + " -20 -20\nedge1 = 0 40 0\nedge2 = 0 0 40\n" + extra;
}

}  // namespace keygrid::test
