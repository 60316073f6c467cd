/** \file MapTool_unittest.cpp
 * keygrid-map info / check on sessions written by the store: the printed meta and counts, exit
 * codes and one-line reasons for another schema version, a damaged file, a dangling reference.
 */
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionStore.h>
#include <sqlite3.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "SyntheticSession.h"
#include "TestData.h"

using namespace keygrid;
using namespace keygrid::store;
using keygrid::test::runCommand;
using keygrid::test::toolPath;

namespace
{
std::string writeSession(const std::string& path)
{
	SessionMeta meta;
	meta.camera = core::RgbdCamera::Preset("fr1");
	meta.vocabulary = {"voc.bin", "00112233445566ff", 9000};
	auto store = SessionStore::Create(path, meta);
	for (KeyFrameId id = 0; id < 3; id++)
	{
		SessionUpdate u;
		u.keyframes.push_back(test::syntheticKeyFrame(id, 30));
		u.keyframes.back().landmarks.assign(30, kNoLandmark);
		u.keyframes.back().landmarks[4] = 100 + id;
		if (id < 2) u.images.push_back(KeyFrameImageCodec().encode(test::syntheticImage(id, true, 64, 48), test::syntheticDepthRaw(id, 64, 48)));
		auto lm = test::syntheticLandmark(100 + id, id, 1);
		lm.observations = {{id, 4}};
		u.landmarks.push_back(lm);
		if (id > 0) u.covisibility.push_back({id - 1, id, 20});
		if (id == 2) u.snapshots.push_back({"map_2d", 2, std::vector<std::uint8_t>(4096, 7)});
		store.write(u);
	}
	return path;
}

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }
}  // namespace

TEST(MapTool, InfoPrintsMetaAndCounts)
{
	const std::string path = writeSession(test::scratchDir("map_tool_info") + "/s.kgmap");
	std::string out;
	ASSERT_EQ(runCommand(toolPath("keygrid-map") + " info " + path, &out), 0) << out;
	for (const char* expected :
		 {"schema_version     1", "vocabulary         voc.bin hash 00112233445566ff words 9000", "camera             fr1 640x480 fx 517.306408 fy 516.469215",
		  "keyframes          3 (2 with images)", "landmarks          3", "covisibility edges 2", "loop constraints   0",
		  "map_2d: 4 KiB, up to keyframe 2"})
		EXPECT_NE(out.find(expected), std::string::npos) << expected << "\n" << out;
	ASSERT_EQ(runCommand(toolPath("keygrid-map") + " --help", &out), 0);
	EXPECT_NE(out.find("keygrid-map check FILE"), std::string::npos) << out;
	EXPECT_EQ(runCommand(toolPath("keygrid-map"), &out), 2) << out;
	EXPECT_EQ(runCommand(toolPath("keygrid-map") + " info", &out), 2) << out;
}

TEST(MapTool, CheckPassesAGoodSessionAndNamesWhatIsWrong)
{
	const std::string dir = test::scratchDir("map_tool_check");
	const std::string good = writeSession(dir + "/good.kgmap");
	std::string out;
	ASSERT_EQ(runCommand(toolPath("keygrid-map") + " check --images " + good, &out), 0) << out;
	EXPECT_NE(out.find("good.kgmap: ok (schema version 1, 3 keyframes, 3 landmarks, 2 covisibility edges, 0 loop constraints, images decoded)"),
			  std::string::npos)
		<< out;

	const auto runSql = [](const std::string& path, const std::string& sql) {
		sqlite3* db = nullptr;
		ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
		ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
		sqlite3_close(db);
	};
	const std::string version = writeSession(dir + "/version.kgmap");
	runSql(version, "UPDATE meta SET value = '7' WHERE key = 'schema_version'");
	EXPECT_EQ(runCommand(toolPath("keygrid-map") + " check " + version, &out), 1) << out;
	EXPECT_EQ(lines(out), 1) << out;
	EXPECT_NE(out.find("version.kgmap' has session schema version 7; this keygrid"), std::string::npos) << out;

	const std::string dangling = writeSession(dir + "/dangling.kgmap");
	runSql(dangling, "DELETE FROM keyframes WHERE id = 1");
	EXPECT_EQ(runCommand(toolPath("keygrid-map") + " check " + dangling, &out), 1) << out;
	EXPECT_NE(out.find("landmark 101 is observed by keyframe 1, which is not stored"), std::string::npos) << out;

	const std::string text = dir + "/text.kgmap";
	std::ofstream(text) << "not a map\n";
	EXPECT_EQ(runCommand(toolPath("keygrid-map") + " check " + text, &out), 1) << out;
	EXPECT_NE(out.find("is not a keygrid session"), std::string::npos) << out;
	EXPECT_EQ(runCommand(toolPath("keygrid-map") + " check " + dir + "/missing.kgmap", &out), 1) << out;
}
