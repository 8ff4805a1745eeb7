/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * Calibration throughput: 20,000 frames (4 antennas × 233 subcarriers, 80 MHz) from the
 * simulator, calibrated on one core (preprocessing, accumulation, PCA, Ceres LM, bearing
 * errors on the kept frames). Target: < 10 s. */
#include <benchmark/benchmark.h>
#include <mrpt_wifi/calib/PhaseCalibrator.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <sstream>

using namespace mrpt_wifi;

namespace
{
struct Drive
{
    std::vector<CObservationWiFiCSI> frames;
    std::vector<mrpt::math::TPose2D> poses;
    mrpt::math::TPoint2D tx;
};

const Drive& drive()
{
    static Drive d = []
    {
        const std::string dir = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/scenarios";
        auto sc = sim::Scenario::fromYamlFile(dir + "/calibration.yaml");
        sc.duration_s = 200;  // 100 Hz → 20,000 frames
        sim::Simulator s(sc);
        s.setOdometryEnabled(false);
        Drive out;
        out.tx = {sc.transmitters[0].pose.x, sc.transmitters[0].pose.y};
        sim::SimEvent ev;
        while (s.next(ev))
            if (ev.kind == sim::SimEvent::Kind::Csi)
            {
                out.frames.push_back(*ev.csi);
                out.poses.push_back(ev.frame.robotPose);
            }
        return out;
    }();
    return d;
}

void BM_Calibrate20kFrames(benchmark::State& state)
{
    const Drive& d = drive();
    const auto array = AntennaArray::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/rt-ac86u.yaml");
    for (auto _ : state)
    {
        calib::FramePreparer prep(array);
        calib::PhaseCalibrator cal(array);
        calib::CalibrationFrame f;
        for (size_t i = 0; i < d.frames.size(); ++i)
            if (prep.prepare(d.frames[i], d.poses[i], d.tx, f) == RejectReason::Accepted)
                cal.add(f);
        auto res = cal.solve(cal.channels().at(0));
        benchmark::DoNotOptimize(res);
        state.counters["frames"] = double(res.diag.frames);
        state.counters["lm_iterations"] = res.diag.iterations;
        state.counters["solve_s"] = res.diag.solveTime_s;
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(d.frames.size()));
}
BENCHMARK(BM_Calibrate20kFrames)->Unit(benchmark::kSecond)->Iterations(2);
}  // namespace

BENCHMARK_MAIN();
