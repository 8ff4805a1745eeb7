/* mrpt_wifi — WiFi channel state information for MRPT.  */
// Benchmark of wifi-localize's filter at the issue-11 input rate: 4 APs × 100 bearings/s.
// One iteration = the LiveLocalizer steps with the bearings of `range(1)` ms (odometry + MRPT's
// particle filter with CWiFiBearingMap, the shipped wifi-localize-emulator.ini's settings,
// range(0) particles; range(2) = 0: without odometry, the unknown-motion model and the track
// solves). realtime_factor = data time / compute time: > 1 keeps up; the pose output rate is
// 1000 / range(1) Hz, the added lag one step's time.
#include <benchmark/benchmark.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/RawlogIO.h>

#include <map>

#include "../apps/SyntheticWorld.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

static void BM_LiveLocalizerStep(benchmark::State& state)
{
    const std::string share = MRPT_WIFI_SOURCE_DIR "/share/localization";
    mrpt::config::CConfigFileMemory ini(
        mrpt::io::file_get_contents(share + "/wifi-localize-emulator.ini"));
    ini.write("LocalizationExperiment", "particles_count", int(state.range(0)));
    ini.write("KLD_options", "KLD_minSampleSize", int(state.range(0)));
    ini.write("KLD_options", "KLD_maxSampleSize", int(state.range(0)));
    ini.write(
        "MetricMap_wifiBearingMap_00_creationOpts", "transmitters_file",
        share + "/kidnapped-aps.yaml");
    LiveLocalizer loc(ini, share);

    loctest::WorldOptions wo;
    wo.duration_s = 60;
    wo.rate_Hz = 100;  // per AP
    const auto w = loctest::makeWorld(
        loctest::makeAps(
            {{0.3, 4.7, -0.785}, {9.7, 4.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}}),
        wo);
    // The synthetic world's APs are the map's, in the same order: give bearings the map's MACs.
    std::map<MacAddress, MacAddress> macOf;
    for (size_t i = 0; i < w.aps.size(); ++i)
        macOf[w.aps.transmitters()[i].mac] = loc.wifiMap().transmitters().transmitters()[i].mac;
    auto bearings = w.bearings;
    for (auto& b : bearings) b.transmitter = macOf.at(b.transmitter);
    const double stepData_s = double(state.range(1)) * 1e-3;
    const bool withOdometry = state.range(2) != 0;
    size_t next = 0, odo = 0;
    double t = w.bearings.front().t;
    for (auto _ : state)
    {
        t += stepData_s;
        if (next >= w.bearings.size()) next = 0, odo = 0, t = w.bearings.front().t + stepData_s;
        while (withOdometry && odo < w.odometry.size() && w.odometry.t[odo] <= t)
        {
            mrpt::obs::CObservationOdometry o;
            o.odometry = mrpt::poses::CPose2D(w.odometry.poses[odo++]);
            loc.addOdometry(o);
        }
        while (next < w.bearings.size() && w.bearings[next].t <= t)
            loc.addBearing(observationFromRecord(bearings[next++]));
        if (!loc.step(t)) state.SkipWithError("no bearing in a step");
        while (loc.step(t))  // the shipped max_bearings_per_step: steps of a few, drained
            ;
    }
    state.counters["realtime_factor"] =
        benchmark::Counter(stepData_s * double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["poses_per_s_of_data"] = 1.0 / stepData_s;
}
BENCHMARK(BM_LiveLocalizerStep)
    ->ArgNames({"particles", "step_ms", "odometry"})
    ->Args({3000, 50, 1})
    ->Args({3000, 20, 1})
    ->Args({5000, 50, 1})
    ->Args({3000, 50, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_MAIN();
