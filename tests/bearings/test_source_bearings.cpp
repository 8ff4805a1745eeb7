/* Bearings from other CSI shapes than the RT-AC86U's 80 MHz: 160 MHz Nexmon captures (the
 * simulator's frames through Nexmon datagrams in a pcap, decoded back, to bearings) and the
 * Intel 5300's 30 grouped subcarriers (the simulator's intel5300 receiver, with ground truth). */
#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <mrpt_wifi/sensor/PcapIO.h>

#include <filesystem>

#include "BearingAccuracy.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::test;

namespace
{
/** Median AoA error [deg] (to the nearer mirror) of `algo` over windows of `n` frames. */
struct Errors
{
    std::vector<double> errors_deg, sigmas_deg;
    double median() const { return percentile(errors_deg, 0.5); }
    double withinThreeSigma() const
    {
        size_t in = 0;
        for (size_t i = 0; i < errors_deg.size(); ++i) in += errors_deg[i] <= 3 * sigmas_deg[i];
        return errors_deg.empty() ? 0 : double(in) / double(errors_deg.size());
    }
};

Errors bearingErrors(
    const std::vector<CObservationWiFiCSI::Ptr>& frames, const std::vector<double>& trueAoa,
    const AntennaArray& rx, const PhaseCalibration& cal, const PreprocessOptions& opts,
    size_t window)
{
    CsiPreprocessor pre(opts, rx, CalibrationStore::fromCalibration(cal));
    auto est = bearing::createEstimator("aoa_only", {});
    bearing::EstimatorContext ctx;
    ctx.rxArray = &rx;
    Errors out;
    std::vector<CleanCsi> clean(window);
    std::vector<const CleanCsi*> ptrs;
    for (size_t first = 0; first + window <= frames.size(); first += window)
    {
        ptrs.clear();
        for (size_t j = 0; j < window; ++j)
            if (pre.process(*frames[first + j], clean[j]) == RejectReason::Accepted)
                ptrs.push_back(&clean[j]);
        bearing::BearingResult r;
        if (ptrs.empty() || !est->estimate(ptrs, ctx, r) || !r.valid) continue;
        const double truth = trueAoa[first + window - 1];
        double err = angleDistance(r.aoa_rad, truth);
        if (r.aoaAmbiguous) err = std::min(err, angleDistance(r.aoaMirror_rad, truth));
        out.errors_deg.push_back(err * 180 / M_PI);
        out.sigmas_deg.push_back(r.aoaStd_rad * 180 / M_PI);
    }
    return out;
}
}  // namespace

// A 160 MHz capture as the 4366c0 would send it (512 words per datagram, chanspec 50/160), made
// by the simulator, written as Nexmon datagrams in a pcap, read back by the decoder registry,
// then preprocessed (per-segment sub-band sign) and turned into bearings against the truth.
TEST(Wide160, SimulatedCaptureRoundTripsThroughNexmonDatagramsToBearings)
{
    sim::Scenario sc = sim::Scenario::fromYamlFile(scenarioPath("bearing"));
    sc.duration_s = 6;
    for (auto& t : sc.transmitters) t.chanspec = Chanspec::fromString("50/160");
    sc.transmitters.resize(1);
    sc.transmitters[0].streams = 1;
    sc.impairments.fixedSnr_dB = 25;
    sc.validate();
    sim::Simulator simulator(sc);
    ASSERT_TRUE(sc.impairments.lowerSubbandSignFlip);

    const auto dir = std::filesystem::path(::testing::TempDir()) / "wide160";
    std::filesystem::create_directories(dir);
    const std::string pcapPath = (dir / "capture.pcap").string();
    std::vector<CObservationWiFiCSI> simulated;
    std::vector<double> trueAoa;
    {
        PcapWriter pcap(pcapPath);
        std::vector<uint8_t> datagram;
        sim::SimEvent ev;
        simulator.setOdometryEnabled(false);
        while (simulator.next(ev) && simulated.size() < 240)
        {
            if (ev.kind != sim::SimEvent::Kind::Csi) continue;
            const auto& obs = *ev.csi;
            for (unsigned m = 0; m < obs.nTx; ++m)
                for (unsigned i = 0; i < obs.nRx; ++i)
                {
                    nexmon::encodeDatagram(nexmon::headerFor(obs, m, i), obs.pair(m, i), datagram);
                    ASSERT_EQ(datagram.size(), nexmon::kHeaderBytes + 4 * 512u);
                    pcap.writeUdp(datagram.data(), datagram.size(), obs.timestamp);
                }
            simulated.push_back(obs);
            trueAoa.push_back(ev.frame.aoa_rad);
        }
    }
    ASSERT_EQ(simulated.size(), 240u);

    std::vector<CObservationWiFiCSI::Ptr> decoded;
    readCsiFrames(
        pcapPath, {}, [&](CObservationWiFiCSI::Ptr&& f) { decoded.push_back(std::move(f)); });
    ASSERT_EQ(decoded.size(), simulated.size());
    for (size_t n = 0; n < decoded.size(); ++n)
    {
        const auto& d = *decoded[n];
        ASSERT_EQ(d.chanspec.bandwidthMHz, 160u);
        ASSERT_EQ(d.nfft(), 512u);
        ASSERT_TRUE(d.isComplete());
        // The decoded words equal the simulated CSI up to the float packing (11-bit mantissa).
        for (unsigned i = 0; i < d.nRx; ++i)
        {
            std::complex<double> dot = 0;
            double a2 = 0, b2 = 0;
            for (int k : dataSubcarriers(160))
            {
                const auto a = std::complex<double>(d.at(0, i, subcarrierToBin(k, 512)));
                const auto b = std::complex<double>(simulated[n].at(0, i, subcarrierToBin(k, 512)));
                dot += a * std::conj(b);
                a2 += std::norm(a);
                b2 += std::norm(b);
            }
            ASSERT_GE(std::abs(dot) / std::sqrt(a2 * b2), 0.9999) << "frame " << n << " rx " << i;
        }
    }

    const AntennaArray rx = fromSimArray(sc.receiver.array);
    const PhaseCalibration cal = truthCalibration(simulator, rx, sc.transmitters[0].chanspec);
    const Errors corrected = bearingErrors(decoded, trueAoa, rx, cal, {}, 4);
    std::cout << "160 MHz round trip: " << corrected.errors_deg.size() << " bearings, median "
              << corrected.median() << " deg, within 3 sigma " << corrected.withinThreeSigma()
              << "\n";
    ::testing::Test::RecordProperty("median_aoa_error_deg", std::to_string(corrected.median()));
    ASSERT_GE(corrected.errors_deg.size(), 55u);
    EXPECT_LE(corrected.median(), 3.0);
    EXPECT_GE(corrected.withinThreeSigma(), 0.9);

    // The per-segment sign: after preprocessing, the phase from one subcarrier to the next is
    // continuous at the sub-band edges k = −193 | −192 and 63 | 64 (~180° without it).
    const auto edgeSteps_deg = [&](const PreprocessOptions& o)
    {
        CsiPreprocessor pre(o, rx, CalibrationStore::fromCalibration(cal));
        CleanCsi c;
        double lo = 0, hi = 0;
        for (const auto& f : decoded)
        {
            EXPECT_EQ(pre.process(*f, c), RejectReason::Accepted);
            const auto& ks = c.layout->subcarriers;
            const auto step = [&](int k)
            {
                const auto j = Eigen::Index(std::find(ks.begin(), ks.end(), k) - ks.begin());
                EXPECT_EQ(ks.at(size_t(j) + 1), k + 1);
                return std::abs(std::arg(c.H.col(j).dot(c.H.col(j + 1)))) * 180 / M_PI;
            };
            lo += step(-193) / double(decoded.size());
            hi += step(63) / double(decoded.size());
        }
        return std::make_pair(lo, hi);
    };
    PreprocessOptions noSign;
    noSign.correctSubbandSign160 = false;
    const auto [loFixed, hiFixed] = edgeSteps_deg({});
    const auto [loRaw, hiRaw] = edgeSteps_deg(noSign);
    std::cout << "phase step at the negated sub-band edges: " << loFixed << " / " << hiFixed
              << " deg corrected, " << loRaw << " / " << hiRaw << " deg without correction\n";
    EXPECT_LT(loFixed, 20.0);
    EXPECT_LT(hiFixed, 20.0);
    EXPECT_GT(loRaw, 150.0);
    EXPECT_GT(hiRaw, 150.0);
}

// The preprocessing works on the frame's own subcarrier list: the layout is that list, the
// Nexmon-only steps don't touch it, and the per-packet slope is found across grouped indices.
TEST(SparseSubcarriers, LayoutIsTheObservationsOwnListAndSlopeIsRemoved)
{
    AntennaArray rx = AntennaArray::fromYamlFile(arrayPath("intel5300-linear-3"));
    const Chanspec cs = Chanspec::fromString("159/40");
    const auto& ks = htGroupedSubcarriers(40);
    // One plane wave from 25° on the array, plus a sampling-time offset of 180 ns (a slope of
    // 0.35 rad per subcarrier: 1.4 rad per group step, beyond the lag-one phase of neighbours).
    const double aoa = 25 * M_PI / 180, sto = 180e-9;
    CObservationWiFiCSI obs;
    obs.chanspec = cs;
    obs.nRx = 3;
    obs.nTx = 1;
    obs.resize(1, 3, cs.nfft());
    obs.source = "iwl5300";
    obs.subcarrierIndices.assign(ks.begin(), ks.end());
    for (unsigned i = 0; i < 3; ++i)
    {
        obs.setPresent(0, i);
        for (int k : ks)
        {
            const double f = subcarrierFrequencyHz(cs, k);
            const auto steer = rx.steeringVector(aoa, f, 3);
            obs.at(0, i, subcarrierToBin(k, cs.nfft())) = std::complex<float>(
                steer[i] * std::polar(1.0, -2 * M_PI * k * kSubcarrierSpacingHz * sto));
        }
    }
    CsiPreprocessor pre({}, rx);
    CleanCsi clean;
    ASSERT_EQ(pre.process(obs, clean), RejectReason::Accepted);
    ASSERT_EQ(clean.layout->size(), 30u);
    EXPECT_TRUE(clean.layout->sourceListed);
    EXPECT_EQ(clean.layout->subcarriers.front(), -58);
    // k = +2 is a measurement here (the Nexmon firmware-overwritten bin is not the Intel's).
    EXPECT_EQ(clean.layout->subcarriers[15], 2);
    EXPECT_NEAR(clean.removedDelay_s, sto, 1e-9);
    // After the slope removal the phase across subcarriers is flat on every antenna.
    for (Eigen::Index r = 0; r < clean.H.rows(); ++r)
        for (Eigen::Index j = 1; j < clean.H.cols(); ++j)
            EXPECT_LT(std::abs(std::arg(clean.H(r, j) * std::conj(clean.H(r, j - 1)))), 0.02)
                << "row " << r << " column " << j;
    // The same list on another frame reuses the layout (estimators key their caches on it).
    CleanCsi again;
    ASSERT_EQ(pre.process(obs, again), RejectReason::Accepted);
    EXPECT_EQ(again.layout, clean.layout);

    auto bad = obs;
    bad.subcarrierIndices[3] = bad.subcarrierIndices[2];
    EXPECT_THROW(pre.process(bad, clean), std::invalid_argument);
}

TEST(SparseSubcarriers, SimulatedIntel5300FramesLookLikeTheCsiTools)
{
    AccuracyCase c;
    c.estimates = 6;
    c.windowFrames = 1;
    const auto d = makeRandomRoomDataset(c, 3, "intel5300");
    ASSERT_EQ(d.rx.size(), 3u);
    for (const auto& w : d.windows)
    {
        const auto& f = w.front();
        EXPECT_EQ(f.source, "iwl5300");
        EXPECT_EQ(f.nRx, 3);
        EXPECT_EQ(f.chanspec.asString(), "159/40");
        ASSERT_EQ(f.dataSubcarriers(), htGroupedSubcarriers(40));
        size_t nonzero = 0;
        for (unsigned m = 0; m < f.nTx; ++m)
            for (unsigned i = 0; i < f.nRx; ++i)
                for (unsigned b = 0; b < f.nfft(); ++b)
                {
                    const auto v = f.at(m, i, b);
                    EXPECT_EQ(v.real(), std::round(v.real()));
                    EXPECT_LE(std::abs(v.real()), 128.f);
                    nonzero += std::abs(v) > 0;
                }
        EXPECT_LE(nonzero, size_t(f.nTx) * f.nRx * 30);
    }
}

// Intel-style receiver (3 antennas, 25 mm, 40 MHz, 30 grouped int8 subcarriers) in random
// development rooms, true offsets as the calibration: bearings valid and σ honest.
TEST(SparseSubcarriers, Intel5300BearingsOnDevelopmentRooms)
{
    std::vector<ErrorRecord> recs;
    for (uint32_t seed : {1u, 2u, 3u})
    {
        AccuracyCase c;
        c.snr_dB = 25;
        c.estimates = 40;
        c.windowFrames = 8;
        const auto d = makeRandomRoomDataset(c, seed, "intel5300");
        collectErrors(d, "default", recs);
    }
    const RoomStats s = summarize(recs);
    std::cout << "intel5300 dev rooms 1-3: " << s.count << " estimates, median (±75°) "
              << s.centralMedian_deg << " p90 " << s.centralP90_deg << ", all " << s.median_deg
              << ", >30° " << 100 * s.beyond30 << " %, within 2σ/3σ " << 100 * s.withinTwoSigma
              << " / " << 100 * s.withinThreeSigma << " %\n";
    ASSERT_GE(s.count, 100u);
    EXPECT_LE(s.centralMedian_deg, 5.0);
    EXPECT_GE(s.withinThreeSigma, 0.9);
}
