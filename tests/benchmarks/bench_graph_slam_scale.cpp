/* mrpt_wifi — WiFi channel state information for MRPT.  */
// Graph SLAM at building scale (issue 56): wifi-graphslam's solve over drive lengths and AP
// counts, with the time and the peak memory of each phase as counters. The world: a 60 x 30 m
// building, APs on its walls and inside, a loop at 0.8 m/s with a stretch through the middle,
// AoA bearings at 5 Hz per AP (3° σ, 3 % outliers, the mirror of a linear array), odometry 2 %
// long with a heading drift of 0.4°/m. Target: time per bearing flat over the lengths.
//   build/bin/bench_graph_slam_scale --benchmark_counters_tabular=true
//   build/bin/bench_graph_slam_scale --benchmark_filter='/30/16/'   # one row
// Arguments: minutes of driving / APs / known APs (1) or estimated (0).
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <string>

#include "SyntheticWorld.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using namespace mrpt_wifi::loctest;

namespace
{
/** `count` APs of the 60 x 30 m building: three of every four 0.3 m inside a wall (spread
 *  evenly along the perimeter, facing in), every fourth inside on a 4 x 2 grid of rooms. */
TransmitterMap buildingAps(size_t count)
{
    TransmitterMap m;
    const double W = 60, H = 30, perimeter = 2 * (W + H);
    const size_t onWalls = count - count / 4;
    size_t wall = 0, inside = 0;
    for (size_t i = 0; i < count; ++i)
    {
        KnownTransmitter t;
        char mac[32];
        std::snprintf(mac, sizeof(mac), "02:00:00:00:%02x:%02x", unsigned(count), unsigned(i + 1));
        t.mac = MacAddress::fromString(mac);
        t.name = "ap" + std::to_string(i + 1);
        t.array = ArrayGeometry::fromElements({{0, -0.039}, {0, -0.013}, {0, 0.013}, {0, 0.039}});
        if (i % 4 != 3 && wall < onWalls)
        {
            double s = (wall++ + 0.5) * perimeter / double(onWalls);
            if (s < W)
                t.pose = {s, 0.3, M_PI / 2};
            else if ((s -= W) < H)
                t.pose = {W - 0.3, s, M_PI};
            else if ((s -= H) < W)
                t.pose = {W - s, H - 0.3, -M_PI / 2};
            else
                t.pose = {0.3, H - (s - W), 0};
        }
        else
        {
            const size_t k = inside++;
            t.pose = {
                7.5 + 15.0 * double(k % 4), 7.5 + 15.0 * double((k / 4) % 2), 0.3 * double(k)};
        }
        m.add(t);
    }
    return m;
}

/** Resident peak of the process [MB]; resetPeak() starts a new peak (Linux: clear_refs 5)
 *  from what the process really holds (freed heap returned first: otherwise an earlier, larger
 *  run's freed memory would count as this one's). */
double peakResidentMB()
{
    std::ifstream f("/proc/self/status");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
    return 0;
}
void resetPeak()
{
    malloc_trim(0);
    std::ofstream("/proc/self/clear_refs") << "5";
}

/** CPU time of this thread [s] (the solve runs on it: threads = 1): phase times that a busy
 *  machine does not inflate. */
double threadCpuSeconds()
{
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/** Short counter names of the phases (GraphSlamResult::phases). */
std::string shortName(const std::string& phase)
{
    static const std::map<std::string, std::string> names = {
        {"placement search", "placement"},
        {"attach bearings to nodes", "attach"},
        {"unknown-AP initialisation", "ap_init"},
        {"graph construction", "build"},
        {"Ceres solve", "solve"},
        {"residual statistics", "residuals"},
        {"grown-stage input", "stage_input"},
        {"AP covariance", "ap_cov"}};
    const auto it = names.find(phase);
    return it == names.end() ? phase : it->second;
}

void BM_GraphSlamBuilding(benchmark::State& state)
{
    const double minutes = double(state.range(0));
    const size_t apCount = size_t(state.range(1));
    const bool known = state.range(2) != 0;
    WorldOptions wo;
    wo.duration_s = minutes * 60;
    wo.speed = 0.8;
    wo.rate_Hz = 5;
    wo.aoaStd = mrpt::DEG2RAD(3.0);
    wo.outliers = 0.03;
    wo.aod = false;
    wo.odoScaleError = 0.02;
    wo.odoYawDrift = mrpt::DEG2RAD(0.4);
    wo.seed = 56;
    wo.loop = {{5, 5}, {55, 5}, {55, 26}, {45, 26}, {45, 16}, {15, 16}, {15, 26}, {5, 26}};
    const auto w = makeWorld(buildingAps(apCount), wo);
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    in.aps = w.aps;
    GraphSlamOptions o;
    o.apsKnown = known;
    o.useAod = false;
    o.threads = 1;  // one core
    // Per phase: CPU seconds (since the previous phase ended: the short steps between phases
    // count to the next one) and the resident peak.
    std::map<std::string, double> cpuSeconds, peakMB;
    double lastCpu = 0;
    o.phaseFinished = [&](const GraphSlamPhase& p)
    {
        const std::string k = shortName(p.name);
        const double now = threadCpuSeconds();
        cpuSeconds[k] += now - lastCpu;
        lastCpu = now;
        peakMB[k] = std::max(peakMB[k], peakResidentMB());
        resetPeak();
    };
    GraphSlamResult r;
    for (auto _ : state)
    {
        cpuSeconds.clear(), peakMB.clear();
        resetPeak();
        lastCpu = threadCpuSeconds();
        r = solveBearingGraph(in, o);
    }
    for (const auto& [k, s] : cpuSeconds) state.counters[k + "_s"] = s;
    for (const auto& [k, mb] : peakMB) state.counters[k + "_MB"] = mb;
    state.counters["bearings"] = double(w.bearings.size());
    state.counters["us_per_bearing"] = 1e6 * r.totalTime_s / double(w.bearings.size());
    state.counters["triangulations"] = double(r.apTriangulations);
    const double odo = absoluteTrajectoryError(w.odometry, w.truth).stats.median;
    const double ate = absoluteTrajectoryError(r.poses, w.truth).stats.median;
    state.counters["ate_median_m"] = ate;
    state.counters["ate_reduction_pct"] = 100 * (odo - ate) / odo;
}
BENCHMARK(BM_GraphSlamBuilding)
    ->ArgNames({"min", "aps", "known"})
    ->ArgsProduct({{5, 15, 30, 60}, {4, 16, 32}, {1, 0}})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();
}  // namespace

BENCHMARK_MAIN();
