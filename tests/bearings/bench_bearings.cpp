/* Speed of the bearing chain, one core, 80 MHz, 4 rx × 4 tx, 180 × 180 grid where one applies.
 * "Per frame": the cost of one estimate when a frame arrives (its own statistics included, the
 * window's older frames' kept with them as in a live or offline stream; the windowed SVD redoes
 * the SVD of its whole window). Run with --benchmark_min_time=... as usual. */
#include <benchmark/benchmark.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/bearing/BearingEstimator.h>

#include <random>

using namespace mrpt_wifi;

namespace
{
AntennaArray array(const std::string& name)
{
    return AntennaArray::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/" + name + ".yaml");
}

/** A 4×4 80 MHz frame: three paths with AoD, noise at 20 dB, STO, sign flip. */
CObservationWiFiCSI makeFrame(const AntennaArray& rx, const AntennaArray& tx, uint32_t seed)
{
    CObservationWiFiCSI o;
    o.chanspec = Chanspec::make(155, 80);
    o.transmitter = MacAddress::fromString("02:00:00:00:01:01");
    o.timestamp = mrpt::Clock::fromDouble(1700000000.0 + seed * 0.01);
    o.resize(4, 4, 256);
    std::mt19937 rng(seed);
    std::normal_distribution<double> n01(0, 0.07);
    struct P
    {
        double aoa, aod, tau, amp;
    } paths[] = {{0.4, -0.3, 20e-9, 1.0}, {-0.9, 0.5, 45e-9, 0.5}, {1.2, 0.1, 70e-9, 0.3}};
    for (unsigned m = 0; m < 4; ++m)
        for (unsigned i = 0; i < 4; ++i)
        {
            o.setPresent(m, i);
            for (int k = -122; k <= 122; ++k)
            {
                const double f = o.chanspec.centerFrequencyHz() + k * 312.5e3;
                std::complex<double> h = 0;
                for (const auto& p : paths)
                    h += p.amp * std::polar(
                                     1.0, -2 * M_PI * f * p.tau + rx.steeringPhase(i, p.aoa, f) +
                                              tx.steeringPhase(m, p.aod, f));
                h += std::complex<double>(n01(rng), n01(rng));
                if (k < -64) h = -h;
                o.at(m, i, unsigned(k + 128)) = std::complex<float>(h);
            }
        }
    return o;
}

struct Fixture
{
    AntennaArray rx = array("rt-ac86u"), tx = array("ap-linear-4");
    CsiPreprocessor pre{PreprocessOptions(), rx};
    std::vector<CObservationWiFiCSI> raw;
    std::vector<CleanCsi> clean;
    Fixture()
    {
        for (uint32_t s = 0; s < 8; ++s) raw.push_back(makeFrame(rx, tx, s + 1));
        clean.resize(raw.size());
        for (size_t n = 0; n < raw.size(); ++n)
            if (pre.process(raw[n], clean[n]) != RejectReason::Accepted)
                throw std::runtime_error("bench_bearings: synthetic frame rejected");
    }
};

void runEstimator(
    benchmark::State& state, const std::string& algo, const std::string& params, unsigned window)
{
    Fixture fx;
    auto est = bearing::createEstimator(
        algo, mrpt::containers::yaml::FromText(params.empty() ? "{}" : params));
    est->options().window = window;
    std::vector<const CleanCsi*> frames;
    for (unsigned n = 0; n < window; ++n) frames.push_back(&fx.clean[n]);
    bearing::EstimatorContext ctx;
    ctx.rxArray = &fx.rx;
    ctx.txArrayOf = [&](const MacAddress&) { return &fx.tx; };
    bearing::BearingResult r;
    if (!est->estimate(frames, ctx, r))  // warm-up: steering matrices
    {
        state.SkipWithError("estimator failed");
        return;
    }
    for (auto _ : state)
    {
        fx.clean[window - 1].invalidateCaches();  // the new frame's statistics are part of the cost
        est->estimate(frames, ctx, r);
        benchmark::DoNotOptimize(r.aoa_rad);
    }
}
}  // namespace

static void BM_Preprocess(benchmark::State& state)
{
    Fixture fx;
    CleanCsi out;
    size_t n = 0;
    for (auto _ : state)
    {
        fx.pre.process(fx.raw[n++ % fx.raw.size()], out);
        benchmark::DoNotOptimize(out.H.data());
    }
}
BENCHMARK(BM_Preprocess)->Unit(benchmark::kMicrosecond);

static void BM_FastAoa(benchmark::State& s)
{
    runEstimator(s, "aoa_only", "angle_bins: 180", 1);
}
BENCHMARK(BM_FastAoa)->Unit(benchmark::kMicrosecond);
static void BM_Profile2D(benchmark::State& s)
{
    runEstimator(s, "fft", "angle_bins: 180\ndelay_bins: 180", 1);
}
BENCHMARK(BM_Profile2D)->Unit(benchmark::kMicrosecond);
static void BM_WindowedSvd8(benchmark::State& s)
{
    runEstimator(s, "svd", "angle_bins: 180\ndelay_bins: 180", 8);
}
BENCHMARK(BM_WindowedSvd8)->Unit(benchmark::kMicrosecond);
static void BM_Music(benchmark::State& s)
{
    runEstimator(s, "music", "angle_bins: 180", 1);
}
BENCHMARK(BM_Music)->Unit(benchmark::kMicrosecond);
static void BM_SpotFi(benchmark::State& s)
{
    runEstimator(s, "spotfi", "angle_bins: 180\ndelay_bins: 180", 1);
}
BENCHMARK(BM_SpotFi)->Unit(benchmark::kMicrosecond);
static void BM_Aod(benchmark::State& s)
{
    runEstimator(s, "aod", "angle_bins: 180", 1);
}
BENCHMARK(BM_Aod)->Unit(benchmark::kMicrosecond);
static void BM_Esprit(benchmark::State& s)
{
    runEstimator(s, "esprit", "", 1);
}
BENCHMARK(BM_Esprit)->Unit(benchmark::kMicrosecond);

void BM_Default8(benchmark::State& s)
{
    runEstimator(s, "default", "", 8);
}
BENCHMARK(BM_Default8)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
