// Render speed of the shipped simulator scenes at 640x480: the ray caster alone
// (BM_Render) and ray caster + Kinect sensor model + raw depth packing (BM_SimulateFrame),
// with 1 and 2 threads. Frames cycle through the scene's trajectory so every view counts.
//   build-x/bin/keygrid_sim_benchmark --benchmark_counters_tabular=true
// The "fps" counter is frames per second of wall time.
#include <benchmark/benchmark.h>
#include <keygrid/sim/Renderer.h>
#include <keygrid/sim/Scene.h>
#include <keygrid/sim/Simulator.h>

#include <map>
#include <memory>
#include <string>

namespace
{
const char* kScenes[] = {
	"room_loop", "corridor_loop", "static_camera_dynamic", "moving_camera_dynamic",
	"relocalization"};

const keygrid::sim::Scene& scene(int i)
{
	static std::map<int, std::unique_ptr<keygrid::sim::Scene>> cache;
	auto& s = cache[i];
	if (!s)
		s = std::make_unique<keygrid::sim::Scene>(keygrid::sim::Scene::loadFromFile(
			std::string(KEYGRID_SOURCE_DIR) + "/config/sim/" + kScenes[i] + ".ini"));
	return *s;
}

void BM_Render(benchmark::State& st)
{
	const auto& sc = scene(static_cast<int>(st.range(0)));
	keygrid::sim::RenderOptions ro;
	ro.threads = static_cast<unsigned>(st.range(1));
	const keygrid::sim::Renderer r(sc, ro);
	keygrid::sim::RenderOutput out;
	std::size_t i = 0;
	for (auto _ : st)
	{
		const std::size_t f = (i++ * 7) % sc.options.frames;  // spread over the whole path
		r.render(sc.cameraPose(f), sc.frameTime(f), out);
		benchmark::DoNotOptimize(out.depth.data);
	}
	st.SetLabel(kScenes[st.range(0)]);
	st.counters["fps"] =
		benchmark::Counter(static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
}

void BM_SimulateFrame(benchmark::State& st)
{
	const auto& sc = scene(static_cast<int>(st.range(0)));
	const keygrid::sim::Simulator sim(sc, static_cast<unsigned>(st.range(1)));
	keygrid::sim::SimFrame f;
	std::size_t i = 0;
	for (auto _ : st)
	{
		sim.frame((i++ * 7) % sc.options.frames, f);
		benchmark::DoNotOptimize(f.frame.depth.data);
	}
	st.SetLabel(kScenes[st.range(0)]);
	st.counters["fps"] =
		benchmark::Counter(static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
}

void sceneArgs(benchmark::internal::Benchmark* b)
{
	b->ArgNames({"scene", "threads"});
	for (int s = 0; s < 5; s++)
		for (int t : {1, 2}) b->Args({s, t});
	b->UseRealTime()->Unit(benchmark::kMillisecond);
}
}  // namespace

BENCHMARK(BM_Render)->Apply(sceneArgs);
BENCHMARK(BM_SimulateFrame)->Apply(sceneArgs);

BENCHMARK_MAIN();
