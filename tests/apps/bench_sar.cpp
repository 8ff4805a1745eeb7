/* mrpt_wifi — WiFi channel state information for MRPT.  */
// Benchmark of issue 18's speed target: one synthetic-aperture bearing (WSR Toolbox: 5.3 s and
// 13–25 GB per estimate in its own output files) in <= 50 ms and <= 200 MB on one core.
//  - BM_SarBearingFromRecording: a real WSR recording (LOS_Set_A, ../shared): pairing by
//    counter, the forward x reverse products, positions from the motion-capture trajectory and
//    the estimate, for one peer (the files decoded once, outside the timing: decoding is the
//    reader's cost, shared by every consumer);
//  - BM_SarBearingSynthetic: the estimate alone on 1 500 synthetic exchanges along a 1 m arc.
// Counter peak_rss_MB: the process's peak resident memory (getrusage) after the runs.
#include <benchmark/benchmark.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/obs/bearing/SyntheticAperture.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <sys/resource.h>

#include <cmath>
#include <filesystem>

#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
double peakRssMB()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

std::vector<CObservationWiFiCSI::Ptr> decode(const std::string& path)
{
    CsiDecodeOptions o;
    o.chanspec = Chanspec::fromString("108");
    std::vector<CObservationWiFiCSI::Ptr> frames;
    decodeCsiFile(path, "auto", o, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); });
    return frames;
}

}  // namespace

static void BM_SarBearingFromRecording(benchmark::State& state)
{
    const std::string loc = test::sharedDir() +
                            "/data/wsr/Dataset/2D-Displacement_raw_data/LOS_Set_A/"
                            "0627_2D-multi-link_A_L1/";
    const std::string s = "2021-06-27_202550";
    if (test::sharedDir().empty() || !std::filesystem::exists(loc))
    {
        state.SkipWithError("WSR recordings not found (../shared absent)");
        return;
    }
    std::vector<CObservationWiFiCSI::Ptr> mover;
    for (const auto& f : decode(loc + "csi_rx_" + s + ".dat"))
        if (f->transmitter.asString() == "00:21:6a:3f:17:5a") mover.push_back(f);
    const auto peer = decode(loc + "csi_tx2_" + s + ".dat");
    const auto traj = localization::Trajectory2D::fromFile(loc + "rx_trajectory_" + s + "_.csv");
    sar::SarOptions options;
    options.carrier_Hz = Chanspec::fromString("108").centerFrequencyHz();
    size_t used = 0;
    for (auto _ : state)
    {
        std::vector<sar::Exchange> ex;
        for (const auto& pp : sar::pairedProducts(mover, peer, 0, 0))
        {
            mrpt::math::TPose2D p;
            if (traj.interpolate(pp.time_s, p, 0.5))
                ex.push_back({pp.time_s, {p.x, p.y}, pp.product});
        }
        std::string why;
        const auto est = sar::estimateBearing(ex, options, why);
        if (!est) state.SkipWithError(why.c_str());
        used = est ? est->packetsUsed : 0;
        benchmark::DoNotOptimize(est);
    }
    state.counters["packets_used"] = double(used);
    state.counters["peak_rss_MB"] = peakRssMB();
}
BENCHMARK(BM_SarBearingFromRecording)->Unit(benchmark::kMillisecond);

static void BM_SarBearingSynthetic(benchmark::State& state)
{
    const double k = 2 * M_PI * 5.54e9 / 299792458.0;
    const mrpt::math::TPoint2D peer(-2.0, 3.0);
    std::vector<sar::Exchange> ex;
    for (int i = 0; i < 1500; ++i)
    {
        const double s = M_PI / 2 * i / 1499.0;
        const mrpt::math::TPoint2D p(0.64 * std::sin(s), 0.64 * (1 - std::cos(s)));
        ex.push_back({0.005 * i, p, std::polar(1.0, -2 * k * (peer - p).norm())});
    }
    sar::SarOptions options;
    options.carrier_Hz = 5.54e9;
    for (auto _ : state)
    {
        std::string why;
        benchmark::DoNotOptimize(sar::estimateBearing(ex, options, why));
    }
    state.counters["peak_rss_MB"] = peakRssMB();
}
BENCHMARK(BM_SarBearingSynthetic)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
