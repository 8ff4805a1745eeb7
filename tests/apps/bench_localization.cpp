/* mrpt_wifi — WiFi channel state information for MRPT.  */
// Benchmarks of the localization targets (issue 7):
//  - particle filter: >= 100 updates/s with 5,000 particles (MRPT's CParticleFilter with the
//    WiFi bearing map; one update = prediction + weighting + resampling for one sensory frame);
//  - graph SLAM: 10,000 poses + 50,000 bearing edges solved in <= 5 s;
//  - the window smoother without odometry: a track solve well inside its 0.5 s period.
#include <benchmark/benchmark.h>
#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/slam/CMonteCarloLocalization2D.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/BearingTrack.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/WindowSmoother.h>

#include "SyntheticWorld.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using namespace mrpt_wifi::loctest;

namespace
{
const TransmitterMap& kidnappedAps()
{
    static const auto aps =
        makeAps({{0.3, 4.7, -0.785}, {9.7, 4.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}});
    return aps;
}
}  // namespace

// range(0): particles, range(1): bearing observations per sensory frame.
static void BM_ParticleFilterUpdate(benchmark::State& state)
{
    WorldOptions wo;
    wo.duration_s = 30;
    const auto w = makeWorld(kidnappedAps(), wo);
    auto map = CWiFiBearingMap::Create();
    map->setTransmitters(kidnappedAps());
    auto mm = std::make_shared<mrpt::maps::CMultiMetricMap>();
    mm->maps.push_back(map);

    mrpt::slam::CMonteCarloLocalization2D pdf;
    pdf.options.metricMap = mm;
    pdf.resetUniform(0, 10, 0, 5, -M_PI, M_PI, size_t(state.range(0)));
    mrpt::bayes::CParticleFilter pf;
    pf.m_options.PF_algorithm = mrpt::bayes::CParticleFilter::pfStandardProposal;
    pf.m_options.BETA = 0.5;
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mo;
    mo.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    mo.gaussianModel.minStdXY = 0.01;
    mo.gaussianModel.minStdPHI = 0.01;
    mrpt::obs::CActionRobotMovement2D act;
    act.computeFromOdometry(mrpt::poses::CPose2D(0.01, 0, 0.001), mo);
    mrpt::obs::CActionCollection acts;
    acts.insert(act);

    const size_t perFrame = size_t(state.range(1));
    std::vector<mrpt::obs::CSensoryFrame> frames;
    for (size_t i = 0; i + perFrame <= w.bearings.size(); i += perFrame)
    {
        mrpt::obs::CSensoryFrame sf;
        for (size_t k = 0; k < perFrame; ++k) sf.insert(observationFromRecord(w.bearings[i + k]));
        frames.push_back(sf);
    }
    size_t i = 0;
    for (auto _ : state)
    {
        pf.executeOn(pdf, &acts, &frames[i++ % frames.size()]);
        benchmark::DoNotOptimize(pdf.ESS());
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
    state.counters["updates_per_s"] =
        benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ParticleFilterUpdate)
    ->Args({5000, 1})
    ->Args({5000, 4})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// 10,000 pose nodes (one per 20 Hz odometry reading → 500 s of driving) and 50,000
// bearing edges (25,000 bearings with AoA + AoD), 4 known APs.
static void BM_GraphSlam10kPoses50kEdges(benchmark::State& state)
{
    WorldOptions wo;
    wo.duration_s = 500;
    wo.rate_Hz = 12.5;  // 4 APs × 12.5 Hz × 500 s = 25,000 bearings
    wo.loop = {{2, 1}, {9, 1}, {9, 5}, {2, 5}};
    const auto aps =
        makeAps({{0.5, 6.5, -0.785}, {10.5, 6.5, -2.36}, {10.5, -0.5, 2.36}, {0.5, -0.5, 0.785}});
    const auto w = makeWorld(aps, wo);
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    in.aps = aps;
    GraphSlamOptions o;
    o.apsKnown = true;
    o.nodePeriod_s = 0.04;  // below the 0.05 s odometry period: one node per reading
    GraphSlamResult r;
    for (auto _ : state) r = solveBearingGraph(in, o);
    state.counters["poses"] = double(r.poses.size());
    state.counters["bearing_edges"] = double(r.aoaEdges + r.aodEdges);
    state.counters["solve_s"] = r.solveTime_s;
    state.counters["iterations"] = r.iterations;
    state.counters["ate_median_m"] = absoluteTrajectoryError(r.poses, w.truth).stats.median;
}
BENCHMARK(BM_GraphSlam10kPoses50kEdges)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// One solve of the window smoother without odometry: a 20 s track (41 nodes) fitted to the
// AoA of 4 APs at range(0) bearings per second each, from a start 0.5 m behind the robot. Live,
// wifi-localize makes one every 0.5 s in its filter thread.
static void BM_TrackSolveWithoutOdometry20s(benchmark::State& state)
{
    WorldOptions wo;
    wo.duration_s = 40;
    wo.rate_Hz = double(state.range(0));
    wo.aod = false;
    wo.multipathAmplitude = 2 * M_PI / 180;
    const auto w = makeWorld(kidnappedAps(), wo);
    TrackInput in;
    in.t1 = w.truth.t.front() + 30, in.t0 = in.t1 - 20;
    in.aps = kidnappedAps(), in.bearings = w.bearings;
    Trajectory2D start;
    for (size_t i = 0; i < w.truth.size(); i += 10)
        start.push_back(
            w.truth.t[i],
            (mrpt::poses::CPose2D(w.truth.poses[i]) + mrpt::poses::CPose2D(-0.5, 0.2, 0.17))
                .asTPose());
    in.starts = {start};
    TrackMotionPrior prior;
    prior.forwardOnly = true;
    auto g = WindowSmootherOptions::defaultGraph();
    g.useAod = false;
    TrackResult r;
    for (auto _ : state) r = solveBearingTrack(in, prior, g);
    std::vector<double> errors;
    for (size_t k = 0; k < r.poses.size(); ++k)
    {
        mrpt::math::TPose2D truth;
        w.truth.interpolate(r.poses.t[k], truth);
        errors.push_back(std::hypot(r.poses.poses[k].x - truth.x, r.poses.poses[k].y - truth.y));
    }
    state.counters["bearing_edges"] = double(r.bearingEdges);
    state.counters["newest_node_error_m"] = errors.back();
    std::nth_element(errors.begin(), errors.begin() + long(errors.size() / 2), errors.end());
    state.counters["median_node_error_m"] = errors[errors.size() / 2];
}
BENCHMARK(BM_TrackSolveWithoutOdometry20s)
    ->Arg(10)
    ->Arg(30)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
