/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * Simulator speed: the reference load, a 10-minute scenario with 4 APs × 100 frames/s,
 * 4 streams × 4 chains, 80 MHz (share/scenarios/kidnapped.yaml), on one core. The counter
 * `speedup_vs_realtime` is simulated seconds per wall-clock second (target ≥ 50). */
#include <benchmark/benchmark.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <chrono>

using namespace mrpt_wifi::sim;

namespace
{
Scenario referenceScenario(double duration_s)
{
    Scenario sc = Scenario::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/scenarios/kidnapped.yaml");
    sc.duration_s = duration_s;
    return sc;
}

/** Whole stream: geometry, synthesis, impairments, noise, odometry, observation objects. */
void BM_TenMinutes_4AP_100Hz_4x4_80MHz(benchmark::State& state)
{
    const double duration = double(state.range(0));
    double simulated = 0, wall = 0;
    uint64_t frames = 0;
    for (auto _ : state)
    {
        state.PauseTiming();
        Simulator sim(referenceScenario(duration));  // setup (trajectory, odometry) not timed
        state.ResumeTiming();
        const auto t0 = std::chrono::steady_clock::now();
        SimEvent ev;
        while (sim.next(ev))
        {
            if (ev.kind == SimEvent::Kind::Csi) ++frames;
            simulated = ev.time_s;
        }
        wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        benchmark::DoNotOptimize(ev.csi->csi.data());
    }
    state.counters["simulated_s"] = simulated;
    state.counters["frames"] = double(frames) / double(state.iterations());
    state.counters["frames_per_s"] = double(frames) / wall;
    state.counters["speedup_vs_realtime"] = simulated * double(state.iterations()) / wall;
    state.counters["us_per_frame"] = wall / double(frames) * 1e6;
}
BENCHMARK(BM_TenMinutes_4AP_100Hz_4x4_80MHz)
    ->Arg(600)
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

/** One frame of the same scene, many times: the per-frame cost alone. */
void BM_SynthesizeFrame_4x4_80MHz(benchmark::State& state)
{
    Simulator sim(referenceScenario(60));
    mrpt_wifi::CObservationWiFiCSI obs;
    FrameTruth truth;
    uint64_t n = 0;
    for (auto _ : state)
    {
        sim.synthesizeFrame(n % 4, n / 4, obs, truth);
        benchmark::DoNotOptimize(obs.csi.data());
        ++n;
    }
    state.counters["paths"] = truth.pathCount;
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_SynthesizeFrame_4x4_80MHz)->Unit(benchmark::kMicrosecond);
}  // namespace

BENCHMARK_MAIN();
