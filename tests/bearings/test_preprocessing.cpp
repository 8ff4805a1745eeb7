/* Preprocessing: sub-band sign quirk (synthetic and real captures), calibration, sampling-time
 * offset, masked bins, RSSI gate, stream selection, windows. */
#include <gtest/gtest.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>

#include <algorithm>

#include "SyntheticCsi.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
/** Largest |phase step − median step| [deg] between neighbouring subcarriers of one row. */
double worstStepDeviation(const CleanCsi& f, Eigen::Index row, int* where = nullptr)
{
    const auto& k = f.layout->subcarriers;
    std::vector<double> steps;
    std::vector<int> at;
    for (size_t j = 0; j + 1 < k.size(); ++j)
        if (k[j + 1] - k[j] == 1)
        {
            steps.push_back(
                std::arg(f.H(row, Eigen::Index(j + 1)) * std::conj(f.H(row, Eigen::Index(j)))));
            at.push_back(k[j]);
        }
    std::vector<double> sorted = steps;
    std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
    const double med = sorted[sorted.size() / 2];
    double worst = 0;
    for (size_t i = 0; i < steps.size(); ++i)
    {
        const double d = std::abs(std::remainder(steps[i] - med, 2 * M_PI)) * 180 / M_PI;
        if (d > worst)
        {
            worst = d;
            if (where) *where = at[i];
        }
    }
    return worst;
}

test::SyntheticSpec oneLosPath()
{
    test::SyntheticSpec s;
    s.rx = test::loadArray("rt-ac86u");
    s.paths = {{0.3, 0, 15e-9, {1, 0}}};
    return s;
}
}  // namespace

TEST(PreprocessSign, SyntheticStepAt65IsRemoved)
{
    auto s = oneLosPath();
    s.signFlip80 = true;
    const auto obs = test::synthesize(s);
    CleanCsi fixed, raw;
    PreprocessOptions off;
    off.correctSubbandSign80 = false;
    ASSERT_EQ(CsiPreprocessor({}, s.rx).process(obs, fixed), RejectReason::Accepted);
    ASSERT_EQ(CsiPreprocessor(off, s.rx).process(obs, raw), RejectReason::Accepted);
    int where = 0;
    EXPECT_GT(worstStepDeviation(raw, 0, &where), 170.0);
    EXPECT_EQ(where, -65);
    EXPECT_LT(worstStepDeviation(fixed, 0), 1.0);
}

TEST(PreprocessCalibration, UndoesPerAntennaOffsets)
{
    auto s = oneLosPath();
    s.rxPhaseOffsets = {0.0, 1.1, -2.0, 2.7};
    const auto obs = test::synthesize(s);
    auto ideal = s;
    ideal.rxPhaseOffsets.clear();
    const auto ref = test::synthesize(ideal);

    PhaseCalibration c;
    c.device = "rt-ac86u";
    c.chanspec = s.chanspec;
    c.subcarriers = dataSubcarriers(80);
    for (double off : s.rxPhaseOffsets) c.phases_rad.emplace_back(c.subcarriers.size(), off);
    CsiPreprocessor calibrated({}, s.rx, CalibrationStore::fromCalibration(c));
    CsiPreprocessor plain({}, s.rx);
    CleanCsi a, b;
    ASSERT_EQ(calibrated.process(obs, a), RejectReason::Accepted);
    ASSERT_EQ(plain.process(ref, b), RejectReason::Accepted);
    EXPECT_TRUE(a.calibrated);
    EXPECT_FALSE(b.calibrated);
    EXPECT_LT((a.H - b.H).norm() / b.H.norm(), 1e-4);
    // The same calibration on a frame of another channel: a clear error, not silence.
    auto other = s;
    other.chanspec = Chanspec::make(42, 80);
    EXPECT_THROW(calibrated.process(test::synthesize(other), a), CalibrationError);
}

TEST(PreprocessSto, RemovesTheCommonLinearPhase)
{
    auto s = oneLosPath();
    s.sto_s = 60e-9;
    const auto withSto = test::synthesize(s);
    s.sto_s = 0;
    const auto without = test::synthesize(s);
    CsiPreprocessor pre({}, s.rx);
    CleanCsi a, b;
    ASSERT_EQ(pre.process(withSto, a), RejectReason::Accepted);
    ASSERT_EQ(pre.process(without, b), RejectReason::Accepted);
    // Same CSI after removal: the offset and the path delay both go, antenna phases stay.
    EXPECT_LT((a.H - b.H).norm() / b.H.norm(), 1e-3);
    EXPECT_NEAR(a.removedDelay_s - b.removedDelay_s, 60e-9, 0.5e-9);
    EXPECT_NEAR(b.removedDelay_s, 15e-9, 0.5e-9);
    // Antenna phase differences are untouched.
    const double before = std::arg(
        withSto.at(0, 1, subcarrierToBin(10, 256)) *
        std::conj(withSto.at(0, 0, subcarrierToBin(10, 256))));
    const auto& k = a.layout->subcarriers;
    const Eigen::Index j = Eigen::Index(std::find(k.begin(), k.end(), 10) - k.begin());
    EXPECT_NEAR(
        std::remainder(std::arg(a.H(1, j) * std::conj(a.H(0, j))) - before, 2 * M_PI), 0.0, 1e-3);
}

TEST(PreprocessSto, EachStreamLosesItsOwnCyclicShiftButKeepsTheAngleOfDeparture)
{
    auto s = oneLosPath();
    s.streams = 2;
    s.tx = test::loadArray("ap-linear-2");
    s.paths[0].aod_rad = 0.5;
    const auto ref = test::synthesize(s);
    auto csd = ref;
    for (unsigned i = 0; i < 4; ++i)  // stream 1 with a −400 ns cyclic shift
        for (int k = -122; k <= 122; ++k)
            csd.at(1, i, subcarrierToBin(k, 256)) *=
                std::complex<float>(std::polar(1.0, 2 * M_PI * k * kSubcarrierSpacingHz * 400e-9));
    CsiPreprocessor pre({}, s.rx);
    CleanCsi a, b;
    ASSERT_EQ(pre.process(ref, a), RejectReason::Accepted);
    ASSERT_EQ(pre.process(csd, b), RejectReason::Accepted);
    EXPECT_LT((a.H - b.H).norm() / a.H.norm(), 1e-3);
    // The phase between the streams at the centre (the AoD) survives.
    const double expected = s.tx.steeringPhase(1, 0.5, s.chanspec.centerFrequencyHz()) -
                            s.tx.steeringPhase(0, 0.5, s.chanspec.centerFrequencyHz());
    const auto& k = a.layout->subcarriers;
    const Eigen::Index j = Eigen::Index(std::find(k.begin(), k.end(), 1 + 2) - k.begin());  // k = 3
    EXPECT_NEAR(
        std::remainder(std::arg(b.H(4, j) * std::conj(b.H(0, j))) - expected, 2 * M_PI), 0.0, 0.02);
}

TEST(PreprocessMask, MaskedBinsAreRepairedAndOverwrittenBinsExcluded)
{
    auto s = oneLosPath();
    auto obs = test::synthesize(s);
    const auto ref = obs;
    // Firmware garbage at k = +2 and a masked (zeroed) bin at k = 40.
    for (unsigned i = 0; i < 4; ++i)
    {
        obs.at(0, i, subcarrierToBin(2, 256)) = {50.f, -80.f};
        obs.at(0, i, subcarrierToBin(40, 256)) = {0.f, 0.f};
    }
    obs.maskedBins = {uint16_t(subcarrierToBin(40, 256))};
    CsiPreprocessor pre({}, s.rx);
    CleanCsi a, b;
    ASSERT_EQ(pre.process(obs, a), RejectReason::Accepted);
    ASSERT_EQ(pre.process(ref, b), RejectReason::Accepted);
    const auto& k = a.layout->subcarriers;
    EXPECT_EQ(std::count(k.begin(), k.end(), 2), 0);
    EXPECT_EQ(k.size(), 233u);
    EXPECT_LT((a.H - b.H).norm() / b.H.norm(), 5e-3);
}

TEST(PreprocessGate, RssiStreamsAndDeadAntennas)
{
    auto s = oneLosPath();
    s.streams = 2;
    s.tx = test::loadArray("ap-linear-2");
    auto obs = test::synthesize(s);
    PreprocessOptions gate;
    gate.minRssi_dBm = -40;
    CleanCsi out;
    EXPECT_EQ(CsiPreprocessor(gate, s.rx).process(obs, out), RejectReason::LowRssi);

    CsiPreprocessor pre({}, s.rx);
    obs.setPresent(1, 2, false);  // stream 1 lost on antenna 2: only stream 0 is used
    ASSERT_EQ(pre.process(obs, out), RejectReason::Accepted);
    EXPECT_EQ(out.nTx, 1u);
    EXPECT_EQ(out.streamIndex, std::vector<uint8_t>{0});
    for (unsigned b = 0; b < 256; ++b) obs.at(0, 3, b) = 0;  // antenna 3 dead in stream 0 too
    EXPECT_EQ(pre.process(obs, out), RejectReason::DeadAntenna);
    obs.setPresent(0, 1, false);
    EXPECT_EQ(pre.process(obs, out), RejectReason::NoCompleteStream);

    CsiPreprocessor small({}, s.rx.firstElements(3));
    EXPECT_EQ(small.process(test::synthesize(s), out), RejectReason::ArrayMismatch);
    EXPECT_THROW(small.checkCompatible(s.chanspec, 4), std::invalid_argument);
}

TEST(PreprocessWindow, KeepsRecentFramesOfOneShape)
{
    auto s = oneLosPath();
    CsiPreprocessor pre({}, s.rx);
    CsiWindow w(4, 0.5);
    std::vector<const CleanCsi*> frames;
    for (int n = 0; n < 6; ++n)
    {
        auto obs = test::synthesize(s);
        obs.timestamp = mrpt::Clock::fromDouble(100.0 + 0.1 * n);
        obs.sequenceNumber = uint16_t(n);
        ASSERT_EQ(pre.process(obs, w.slot()), RejectReason::Accepted);
        w.commit();
    }
    EXPECT_EQ(w.size(), 4u);
    w.recent(3, frames);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(frames.front()->sequenceNumber, 3);
    EXPECT_EQ(frames.back()->sequenceNumber, 5);
    // Frames older than maxAge (0.5 s) are left out.
    auto late = test::synthesize(s);
    late.timestamp = mrpt::Clock::fromDouble(100.95);
    ASSERT_EQ(pre.process(late, w.slot()), RejectReason::Accepted);
    w.commit();
    w.recent(4, frames);
    EXPECT_EQ(frames.size(), 2u);  // 100.5 and 100.95
    // Another channel flushes the window.
    auto other = s;
    other.chanspec = Chanspec::make(42, 80);
    auto o2 = test::synthesize(other);
    o2.timestamp = mrpt::Clock::fromDouble(101.0);
    ASSERT_EQ(pre.process(o2, w.slot()), RejectReason::Accepted);
    w.commit();
    EXPECT_EQ(w.size(), 1u);
}
