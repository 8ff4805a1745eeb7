/* mrpt_wifi — WiFi channel state information for MRPT.  */
// Benchmarks of the localization targets (issue 7):
//  - particle filter: >= 100 updates/s with 5,000 particles (MRPT's CParticleFilter with the
//    WiFi bearing map; one update = prediction + weighting + resampling for one sensory frame);
//  - graph SLAM: 10,000 poses + 50,000 bearing edges solved in <= 5 s.
#include <benchmark/benchmark.h>
#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/slam/CMonteCarloLocalization2D.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/RawlogIO.h>

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

BENCHMARK_MAIN();
