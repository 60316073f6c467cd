// The maps of a run come from the INI's [MappingApplication] section, keygrid's plugins and
// MRPT's own maps alike; mistakes that MRPT would ignore are reported by name.
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/slam/MetricMaps.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include "TestData.h"

using namespace keygrid;

TEST(MetricMaps, CreatesOurPluginsAndMrptMapsFromTheIni)
{
	mrpt::config::CConfigFileMemory ini(
		"[MappingApplication]\n"
		"ismOccupancyGrid2D_count = 1\n"
		"submappedOccupancyGrid3D_count = 1\n"
		"occupancyGrid_count = 1\n"
		"[MappingApplication_ismOccupancyGrid2D_00_creationOpts]\n"
		"resolution = 0.10\n");
	const slam::MetricMaps maps(ini, {});
	ASSERT_EQ(maps.size(), 3u);
	int ism = 0, g3 = 0, mrptGrid = 0;
	for (const auto& m : maps.maps().maps)
	{
		if (auto* p = dynamic_cast<const CISMOccupancyGrid2D*>(m.get()))
		{
			++ism;
			EXPECT_DOUBLE_EQ(p->resolution(), 0.10);
		}
		g3 += dynamic_cast<const CSubmappedOccupancyGrid3D*>(m.get()) != nullptr;
		mrptGrid += dynamic_cast<const mrpt::maps::COccupancyGridMap2D*>(m.get()) != nullptr;
	}
	EXPECT_EQ(ism, 1);
	EXPECT_EQ(g3, 1);
	EXPECT_EQ(mrptGrid, 1);
}

TEST(MetricMaps, UnknownMapTypeIsNamed)
{
	mrpt::config::CConfigFileMemory ini("[MappingApplication]\nismOccupancyGrid2d_count = 1\n");
	try
	{
		slam::MetricMaps maps(ini, {});
		FAIL() << "a misspelt map type must not be ignored";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("ismOccupancyGrid2d_count"), std::string::npos) << e.what();
	}
	mrpt::config::CConfigFileMemory none("[slam]\nmode = sequential\n");
	EXPECT_TRUE(slam::MetricMaps(none, {}).empty());
	slam::MapFeedOptions feed;
	mrpt::config::CConfigFileMemory bad("[maps]\nism2d_input = sometimes\n");
	EXPECT_THROW(feed.loadFromConfigFile(bad, "maps"), std::invalid_argument);
}
