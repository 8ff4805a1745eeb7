/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * Pieces of the calibration: pose interpolation, TUM and transmitter files, the bearing scan,
 * the solver on synthetic snapshots with known phases. */
#include <gtest/gtest.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/calib/BearingScan.h>
#include <mrpt_wifi/calib/CalibrationCheck.h>
#include <mrpt_wifi/calib/CalibrationInput.h>
#include <mrpt_wifi/calib/CalibrationReport.h>
#include <mrpt_wifi/calib/PhaseCalibrator.h>
#include <mrpt_wifi/obs/ChainStates.h>

#include <fstream>
#include <random>

#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::calib;

namespace
{
AntennaArray rtac86u()
{
    return AntennaArray::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/rt-ac86u.yaml");
}

std::string tempFile(const std::string& name, const std::string& text)
{
    const std::string path = mrpt_wifi::test::tempPath() + "_" + name;
    std::ofstream(path) << text;
    return path;
}

std::shared_ptr<SubcarrierLayout> layout80(unsigned centre)
{
    CsiPreprocessor pre(calibrationPreprocessOptions(), rtac86u());
    auto l = pre.layoutFor(Chanspec::make(centre, 80));
    return std::const_pointer_cast<SubcarrierLayout>(l);
}

/** A synthetic frame: plane wave from θ through hardware phases phi[i](k), common random
 *  phase/delay, complex noise of the given SNR. */
CalibrationFrame syntheticFrame(
    const AntennaArray& a, const std::shared_ptr<SubcarrierLayout>& layout, double theta,
    const std::vector<std::vector<double>>& phi, double snr_dB, std::mt19937& rng, double t)
{
    CalibrationFrame f;
    f.time_s = t;
    f.chanspec = layout->chanspec;
    f.layout = layout;
    f.nRx = 4;
    f.nTx = 1;
    f.hasGeometry = true;
    f.expectedAoa_rad = theta;
    f.distance_m = 3;
    f.H.resize(4, Eigen::Index(layout->size()));
    std::uniform_real_distribution<double> u(-M_PI, M_PI);
    std::normal_distribution<double> g(0, std::sqrt(0.5 * std::pow(10, -snr_dB / 10)));
    const double common = u(rng), delay = 30e-9 * u(rng);
    for (size_t j = 0; j < layout->size(); ++j)
        for (unsigned i = 0; i < 4; ++i)
        {
            const double ph = a.steeringPhase(i, theta, layout->frequencies_Hz[j]) + phi[i][j] +
                              common - 2 * M_PI * layout->subcarriers[j] * 312.5e3 * delay;
            f.H(i, Eigen::Index(j)) =
                std::complex<float>(std::polar(1.0, ph) + std::complex<double>(g(rng), g(rng)));
        }
    return f;
}
}  // namespace

TEST(CalibUnits, PoseTrackInterpolatesAndRefusesGaps)
{
    PoseTrack t;
    t.add(2.0, {2, 0, M_PI - 0.1});
    t.add(1.0, {0, 0, 0});  // out of order: sorted on lookup
    t.add(3.0, {2, 2, -M_PI + 0.1});
    t.add(10.0, {5, 5, 0});
    mrpt::math::TPose2D p;
    ASSERT_TRUE(t.at(1.5, p));
    EXPECT_NEAR(p.x, 1.0, 1e-12);
    EXPECT_NEAR(p.phi, 0.5 * (M_PI - 0.1), 1e-12);
    ASSERT_TRUE(t.at(2.5, p));  // heading through ±π, not through 0
    EXPECT_NEAR(std::abs(p.phi), M_PI, 1e-9);
    EXPECT_FALSE(t.at(0.5, p));  // before the track
    EXPECT_FALSE(t.at(5.0, p));  // 7 s gap > maxGap
    const PoseTrack moved = t.transformed({1, 2, M_PI / 2});
    ASSERT_TRUE(moved.at(2.0, p));
    EXPECT_NEAR(p.x, 1.0, 1e-9);  // (2,0) rotated by 90° → (0,2), shifted by (1,2)
    EXPECT_NEAR(p.y, 4.0, 1e-9);
}

TEST(CalibUnits, TumAndTransmitterFiles)
{
    const auto tum = tempFile(
        "traj.txt",
        "# comment\n100.0 1 2 0 0 0 0.7071067811865476 0.7071067811865476\n"
        "101.0 2 2 0 0 0 0 1\n");
    const PoseTrack t = PoseTrack::fromTumFile(tum);
    mrpt::math::TPose2D p;
    ASSERT_TRUE(t.at(100.0, p));
    EXPECT_NEAR(p.phi, M_PI / 2, 1e-9);
    EXPECT_THROW(PoseTrack::fromTumFile(tempFile("bad.txt", "1 2 3\n")), std::runtime_error);

    const auto sites = loadTransmitterSites(tempFile(
        "tx.yaml",
        "transmitters:\n  - name: a\n    mac: '02:11:22:33:44:01'\n    position: [1.5, -2]\n"
        "    channel: 155/80\n  - mac: 02:11:22:33:44:02\n    position: [0, 0]\n"));
    ASSERT_EQ(sites.size(), 2u);
    EXPECT_EQ(sites[0].mac->asString(), "02:11:22:33:44:01");
    EXPECT_DOUBLE_EQ(sites[0].position.y, -2.0);
    EXPECT_EQ(sites[1].name, "tx1");
    EXPECT_THROW(
        loadTransmitterSites(
            tempFile("tx2.yaml", "transmitters:\n  - mac: zz\n    position: [0, 0]\n")),
        std::runtime_error);
    EXPECT_THROW(
        loadTransmitterSites(tempFile("tx3.yaml", "transmitters:\n  - mac: 02:11:22:33:44:01\n")),
        std::runtime_error);
}

TEST(CalibUnits, BearingScanFindsPlaneWaveAndFoldsMirror)
{
    const auto a = rtac86u();
    auto layout = layout80(155);
    std::mt19937 rng(3);
    const std::vector<std::vector<double>> zero(4, std::vector<double>(layout->size(), 0.0));
    BearingScan scan(a, *layout, 4);
    for (double deg : {-70.0, -20.0, 0.0, 33.3, 61.0})
    {
        const auto f = syntheticFrame(a, layout, deg * M_PI / 180, zero, 30, rng, 0);
        EXPECT_NEAR(scan.estimate(f.H, 1, nullptr) * 180 / M_PI, deg, 0.3) << deg;
    }
    // The array lies along y: 150° is the mirror of 30° across its axis.
    EXPECT_NEAR(scan.fold(150 * M_PI / 180) * 180 / M_PI, 30, 1e-9);
}

// Known phases, plane waves from many bearings, common random phase/delay per packet: the
// solver must return the phases (relative to antenna 0) and undo the bearing errors.
TEST(CalibUnits, SolverRecoversSyntheticPhases)
{
    const auto a = rtac86u();
    auto layout = layout80(42);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-M_PI, M_PI);
    std::vector<std::vector<double>> phi(4, std::vector<double>(layout->size()));
    const double off[4] = {0.3, -2.0, 2.9, 1.1};
    for (unsigned i = 0; i < 4; ++i)
        for (size_t j = 0; j < layout->size(); ++j)
            phi[i][j] = off[i] + 0.1 * i * std::sin(layout->subcarriers[j] / 30.0);
    PhaseCalibrator cal(a);
    for (int n = 0; n < 3000; ++n)
        cal.add(syntheticFrame(a, layout, u(rng) / 2, phi, 15, rng, 0.01 * n));
    const auto res = cal.solve(cal.channels().at(0));
    double worst = 0;
    for (unsigned i = 1; i < 4; ++i)
        for (size_t j = 0; j < layout->size(); ++j)
            worst = std::max(
                worst,
                std::abs(wrapAngle(res.calibration.phases_rad[i][j] - (phi[i][j] - phi[0][j]))));
    EXPECT_LT(worst * 180 / M_PI, 1.0);
    EXPECT_LT(quantile(res.bearingErrorAfter_deg, 0.5), 0.5);
    EXPECT_GT(quantile(res.bearingErrorBefore_deg, 0.5), 5.0);
    EXPECT_EQ(res.calibration.framesUsed, 3000u);
    for (double v : res.calibration.phases_rad[0]) EXPECT_EQ(v, 0.0);  // antenna 0 fixed

    // The file it makes round-trips through the format and applies like the solver's phases.
    const std::string dir = mrpt_wifi::test::tempPath() + "_caldir";
    const std::string path = PhaseCalibration::pathFor(dir, a.name, res.calibration.chanspec);
    res.calibration.saveYamlFile(path);
    const auto store = CalibrationStore::open(dir);
    const PhaseCalibration* back = store.find(a.name, res.calibration.chanspec, 4);
    ASSERT_NE(back, nullptr);
    EXPECT_NEAR(back->phaseAt(2, layout->subcarriers[10]), res.calibration.phases_rad[2][10], 1e-6);

    // Report pictures are written.
    const auto pngs = writeCalibrationReport(res, dir + "/report");
    ASSERT_EQ(pngs.size(), 2u);
    for (const auto& p : pngs) EXPECT_GT(mrpt::system::getFileSize(p), 10000u) << p;
}

TEST(CalibUnits, RejectsMismatchedFrames)
{
    const auto a = rtac86u().firstElements(2);
    PhaseCalibrator cal(a);
    auto layout = layout80(155);
    std::mt19937 rng(1);
    const std::vector<std::vector<double>> zero(4, std::vector<double>(layout->size(), 0.0));
    auto f = syntheticFrame(rtac86u(), layout, 0.2, zero, 20, rng, 0);
    EXPECT_THROW(cal.add(f), std::invalid_argument);  // 4 chains, 2 elements
    PhaseCalibrator drive(rtac86u());
    f.hasGeometry = false;
    EXPECT_THROW(drive.add(f), std::invalid_argument);  // drive mode needs a bearing
    EXPECT_THROW(drive.solve(Chanspec::make(155, 80)), std::runtime_error);  // no frames
}

TEST(CalibUnits, Quantile)
{
    EXPECT_DOUBLE_EQ(quantile({3, 1, 2}, 0.5), 2);
    EXPECT_DOUBLE_EQ(quantile({5}, 0.9), 5);
    EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
}

TEST(CalibUnits, ChainStatesThatDifferByADelayAloneAreNotWritten)
{
    // Issue 54: the muTrack RT-AC86Us' states are sample slips (12.5 ns at 20 MHz, the phase at
    // the centre unchanged): the offsets hold in every state, and a state table would withhold
    // bearings from over-the-air frames whose delays can't be matched to it.
    PhaseCalibration c;
    c.chainStates.resize(2);
    c.chainStates[1].state = 1;
    c.chainStates[1].deltaDelay_s = 12.8e-9;
    c.chainStates[1].deltaPhase_rad = 0.4 * M_PI / 180;
    PhaseCalibration a = c;
    EXPECT_NE(
        applyChainStatePolicy(a, ChainStatePolicy::Auto).find("delay alone"), std::string::npos);
    EXPECT_TRUE(a.chainStates.empty());
    // The file says so, and a tracker built on it doesn't warn that it "holds no jump states".
    EXPECT_TRUE(a.chainStatesDelayOnly);
    a.device = "rt-ac86u-3core-57mm";
    a.chanspec = Chanspec::make(6, 20);
    a.subcarriers = {-2, 2};
    a.phases_rad.assign(3, {0.0, 0.0});
    const auto text = a.asYamlText();
    EXPECT_NE(text.find("chain_states_delay_only: true"), std::string::npos) << text;
    const auto back = PhaseCalibration::fromYamlText(text);
    EXPECT_TRUE(back.chainStatesDelayOnly);
    ChainStateTracker quiet(3, &back, {}, 20);
    std::vector<uint8_t> states;
    for (int i = 0; i < 40; ++i) quiet.classify({0.0, 6e-9, -6e-9}, {1.0, 1.0, 1.0}, states);
    for (const auto& n : quiet.takeNotices())
        EXPECT_EQ(n.find("holds no jump states"), std::string::npos) << n;
    PhaseCalibration plain = back;
    plain.chainStatesDelayOnly = false;
    ChainStateTracker warns(3, &plain, {}, 20);
    for (int i = 0; i < 40; ++i) warns.classify({0.0, 6e-9, -6e-9}, {1.0, 1.0, 1.0}, states);
    bool warned = false;
    for (const auto& n : warns.takeNotices())
        warned |= n.find("holds no jump states") != std::string::npos;
    EXPECT_TRUE(warned);
    a = c;
    EXPECT_TRUE(applyChainStatePolicy(a, ChainStatePolicy::Always).empty());
    EXPECT_FALSE(a.chainStatesDelayOnly);
    EXPECT_EQ(a.chainStates.size(), 2u);
    // A state with a phase of its own (the 80 MHz simulator's, nexmon_csi reports) is kept.
    c.chainStates[1].deltaPhase_rad = 0.5;
    a = c;
    EXPECT_TRUE(applyChainStatePolicy(a, ChainStatePolicy::Auto).empty());
    EXPECT_EQ(a.chainStates.size(), 2u);
    EXPECT_FALSE(applyChainStatePolicy(a, ChainStatePolicy::Never).empty());
    EXPECT_TRUE(a.chainStates.empty());
    EXPECT_EQ(chainStatePolicyFromString("on", "x"), ChainStatePolicy::Always);
    EXPECT_THROW(chainStatePolicyFromString("yes", "--chain-states"), std::invalid_argument);
}
