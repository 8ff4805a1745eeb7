/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * Phase calibration against the simulator's injected per-chain offsets: accuracy, bearings on a
 * separate drive, the three 80 MHz channels, staleness after a reboot, robustness, warnings,
 * the splitter mode. */
#include <gtest/gtest.h>
#include <mrpt_wifi/calib/CalibrationCheck.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <map>
#include <set>

#include "CalibTestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::calib;
using calibtest::DriveSpec;

namespace
{
/** Calibrates on one drive; returns the result and keeps the simulator for its hardware. */
ChannelCalibration calibrate(
    const DriveSpec& d, std::unique_ptr<sim::Simulator>& simOut, CalibratorOptions opts = {})
{
    simOut = std::make_unique<sim::Simulator>(calibtest::scenario(d));
    FramePreparer prep(calibtest::arrayOf(d));
    if (d.splitter) opts.mode = CalibrationMode::Splitter;
    PhaseCalibrator cal(calibtest::arrayOf(d), opts);
    calibtest::driveFrames(
        *simOut, prep, d.splitter,
        [&](const CalibrationFrame& f, const sim::FrameTruth&) { cal.add(f); });
    EXPECT_EQ(cal.channels().size(), 1u);
    return cal.solve(cal.channels().at(0));
}

/** Frames of a drive (every `stride`-th), for bearing errors and checks. */
std::vector<CalibrationFrame> frames(
    sim::Simulator& sim, size_t stride = 10, const AntennaArray& array = calibtest::rtac86u())
{
    FramePreparer prep(array);
    std::vector<CalibrationFrame> out;
    size_t i = 0;
    sim.rewind(0);
    calibtest::driveFrames(
        sim, prep, false,
        [&](const CalibrationFrame& f, const sim::FrameTruth&)
        {
            if (i++ % stride == 0) out.push_back(f);
        });
    return out;
}

/** The separate test drive: same receiver hardware (same seed), another path and start. */
DriveSpec testDriveOf(DriveSpec d)
{
    d.startX = 4.0;
    d.startY = 3.0;
    d.startYaw_deg = 30;
    d.centerX = 6.0;
    d.centerY = 4.5;
    d.duration_s = 40;
    return d;
}
}  // namespace

class CalibSimChannels : public ::testing::TestWithParam<std::string>
{
};

// At 20 dB with moderate multipath, on 36/80 (Broadcom notation: centre 42), 106/80, 155/80.
TEST_P(CalibSimChannels, RecoversOffsetsAndFixesBearingsOnSeparateDrive)
{
    DriveSpec d;
    d.channel = GetParam();
    std::unique_ptr<sim::Simulator> sim;
    const ChannelCalibration res = calibrate(d, sim);
    const auto& c = res.calibration;
    const Chanspec expected = Chanspec::fromString(GetParam());
    EXPECT_EQ(c.chanspec.centerChannel, expected.centerChannel);
    EXPECT_TRUE(res.determined()) << (res.warnings.empty() ? "" : res.warnings.front());

    const double rms = calibtest::phaseErrorRms_deg(c, sim->hardware());
    std::cout << "[ " << GetParam() << " ] offset RMS error " << rms << " deg, residual "
              << c.residual_rad * 180 / M_PI << " deg, LM " << res.diag.iterations << " it\n";
    EXPECT_LT(rms, 3.0);
    // Gains: the simulator's per-chain mismatch (σ 0.5 dB) within 0.5 dB.
    for (unsigned i = 1; i < 4; ++i)
        EXPECT_NEAR(
            c.gainAt(i),
            sim->hardware().chain(c.chanspec, i).gain_dB -
                sim->hardware().chain(c.chanspec, 0).gain_dB,
            0.5);

    // A separate drive with the same hardware: bearings before/after.
    sim::Simulator test(calibtest::scenario(testDriveOf(d)));
    const auto tf = frames(test);
    ASSERT_GT(tf.size(), 200u);
    const double before = quantile(bearingErrors_deg(tf, calibtest::rtac86u(), nullptr), 0.5);
    const double after = quantile(bearingErrors_deg(tf, calibtest::rtac86u(), &c), 0.5);
    std::cout << "[ " << GetParam() << " ] test drive median bearing error " << before << " -> "
              << after << " deg (" << tf.size() << " frames)\n";
    EXPECT_LE(after, 2.0);
    EXPECT_GT(before, 3 * after);
}

INSTANTIATE_TEST_SUITE_P(
    Calib, CalibSimChannels, ::testing::Values("36/80", "106/80", "155/80"),
    [](const auto& p)
    {
        std::string s = p.param;
        for (auto& ch : s)
            if (ch == '/') ch = '_';
        return "ch" + s;
    });

// Any source whose array geometry is given: an Intel 5300-style receiver (3 antennas 25 mm
// apart, 40 MHz, only the 30 grouped subcarriers, int8 CSI) calibrates like the RT-AC86U.
TEST(CalibSim, IntelStyleThreeAntennaSparseSource)
{
    DriveSpec d;
    d.channel = "159/40";
    d.array = "intel5300-linear-3";
    d.csiFormat = "intel5300";
    d.duration_s = 40;
    std::unique_ptr<sim::Simulator> sim;
    const ChannelCalibration res = calibrate(d, sim);
    const auto& c = res.calibration;
    EXPECT_TRUE(res.determined()) << (res.warnings.empty() ? "" : res.warnings.front());
    ASSERT_EQ(c.antennas(), 3u);
    EXPECT_EQ(c.subcarriers, htGroupedSubcarriers(40));
    const double rms = calibtest::phaseErrorRms_deg(c, sim->hardware());

    const auto array = calibtest::arrayOf(d);
    sim::Simulator test(calibtest::scenario(testDriveOf(d)));
    const auto tf = frames(test, 10, array);
    ASSERT_GT(tf.size(), 200u);
    const double before = quantile(bearingErrors_deg(tf, array, nullptr), 0.5);
    const double after = quantile(bearingErrors_deg(tf, array, &c), 0.5);
    std::cout << "[ intel5300 159/40 ] offset RMS error " << rms
              << " deg; test drive median bearing error " << before << " -> " << after << " deg ("
              << tf.size() << " frames)\n";
    ::testing::Test::RecordProperty("intel5300_offset_rms_deg", std::to_string(rms));
    EXPECT_LT(rms, 3.0);
    EXPECT_LE(after, 3.0);
    EXPECT_GT(before, 3 * after);
}

TEST(CalibSim, OldFileIsStaleAfterReboot)
{
    DriveSpec d;
    std::unique_ptr<sim::Simulator> sim;
    const ChannelCalibration res = calibrate(d, sim);
    const auto array = calibtest::rtac86u();

    sim::Simulator test(calibtest::scenario(testDriveOf(d)));
    const auto fresh = frames(test);
    const CheckResult ok = calibrationResidual(fresh, array, res.calibration);
    std::cout << "fresh  : " << ok.message << "\n";
    EXPECT_TRUE(ok.enoughFrames);
    EXPECT_FALSE(ok.stale);

    test.reboot();  // new per-chain offsets
    const auto rebooted = frames(test);
    const CheckResult bad = calibrationResidual(rebooted, array, res.calibration);
    std::cout << "reboot : " << bad.message << "\n";
    EXPECT_TRUE(bad.stale);
    EXPECT_GT(bad.medianError_deg, 5 * ok.medianError_deg);
    EXPECT_GT(bad.phaseResidual_rad, 3 * ok.phaseResidual_rad);
    EXPECT_NE(bad.message.find("recalibrate"), std::string::npos);
}

// Frames whose expected bearing is wrong (a reflection that dominates, a pose glitch) must not
// drag the calibration: the Cauchy loss on segments keeps it within the 3° budget.
TEST(CalibSim, RobustToOutlierSegments)
{
    DriveSpec d;
    d.duration_s = 60;
    auto run = [&](double robustScale)
    {
        sim::Simulator sim(calibtest::scenario(d));
        FramePreparer prep(calibtest::rtac86u());
        CalibratorOptions o;
        o.robustScale = robustScale;
        o.checkFrames = 0;
        PhaseCalibrator cal(calibtest::rtac86u(), o);
        calibtest::driveFrames(
            sim, prep, false,
            [&](const CalibrationFrame& f, const sim::FrameTruth& t)
            {
                CalibrationFrame g = f;
                // 25 % of the time (2 s of every 8 s) the geometry is off by 50°.
                if (std::fmod(t.time_s, 8.0) < 2.0)
                    g.expectedAoa_rad = wrapAngle(g.expectedAoa_rad + 50 * M_PI / 180);
                cal.add(g);
            });
        const auto res = cal.solve(cal.channels().at(0));
        return calibtest::phaseErrorRms_deg(res.calibration, sim.hardware());
    };
    const double robust = run(0.3), plain = run(0.0);
    std::cout << "25 % outlier segments: offset RMS error robust " << robust
              << " deg, least squares " << plain << " deg\n";
    EXPECT_LT(robust, 3.0);
    EXPECT_LT(robust, plain);
}

TEST(CalibSim, WarnsWhenTheDriveCannotDetermineIt)
{
    std::unique_ptr<sim::Simulator> sim;
    {
        DriveSpec d;  // the robot never moves: one bearing
        d.motion = "static";
        d.duration_s = 30;
        const auto res = calibrate(d, sim);
        ASSERT_FALSE(res.determined());
        EXPECT_NE(res.warnings.front().find("distinct bearings"), std::string::npos)
            << res.warnings.front();
    }
    {
        DriveSpec d;  // too short
        d.duration_s = 2;
        const auto res = calibrate(d, sim);
        ASSERT_FALSE(res.determined());
        bool shortWarn = false;
        for (const auto& w : res.warnings) shortWarn |= w.find("lasts only") != std::string::npos;
        EXPECT_TRUE(shortWarn);
    }
    {
        DriveSpec d;  // line of sight blocked around the transmitter (open away from the robot)
        d.blockLos = true;
        d.centerX = 3.5;
        d.startX = 3.5;
        d.radius_m = 2.5;
        d.duration_s = 40;
        const auto res = calibrate(d, sim);
        bool los = false;
        for (const auto& w : res.warnings) los |= w.find("line of sight") != std::string::npos;
        EXPECT_TRUE(los) << "LoS share " << res.diag.losShare;
        std::cout << "blocked line of sight: LoS share " << res.diag.losShare << "\n";
    }
    {
        DriveSpec d;  // transmitter far away in a corner
        d.txX = 0.5;
        d.txY = 0.5;
        d.centerX = 11.5;
        d.centerY = 7.5;
        d.startX = 11.5;
        d.startY = 7.5;
        d.radius_m = 2.0;
        d.duration_s = 30;
        const auto res = calibrate(d, sim);
        bool far = false;
        for (const auto& w : res.warnings) far |= w.find("m away") != std::string::npos;
        EXPECT_TRUE(far) << "median distance " << res.diag.medianDistance_m;
    }
    {
        DriveSpec d;  // a good drive warns about nothing
        d.duration_s = 40;
        const auto res = calibrate(d, sim);
        EXPECT_TRUE(res.determined()) << (res.warnings.empty() ? "" : res.warnings.front());
    }
}

TEST(CalibSim, StaticSplitterRecoversOffsetsDirectly)
{
    DriveSpec d;
    d.splitter = true;
    d.motion = "static";
    d.multipath = false;
    d.duration_s = 20;
    std::unique_ptr<sim::Simulator> sim;
    const auto res = calibrate(d, sim);
    const double rms = calibtest::phaseErrorRms_deg(res.calibration, sim->hardware());
    std::cout << "splitter: offset RMS error " << rms << " deg\n";
    EXPECT_LT(rms, 1.0);
    EXPECT_TRUE(res.bearingErrorAfter_deg.empty());  // no geometry in this mode
}

// Issue 21: a drive whose receive chains jump among three states (3 ns apart, each with its own
// phase, switching at 0.1 Hz). The calibrator groups the same drive by state and solves every
// state's offsets. The frames carry the simulator's true states here, so this checks the
// per-state solve itself; the per-frame classifier is tested in test_chain_states.
namespace
{
struct PerStateResult
{
    size_t states = 0, visited = 0;
    double rms_deg = 0;
};

/** A calibration drive with jump states (3 states, 3 ns apart, each with its own phase, 0.1 Hz):
 *  the calibrator's per-state offsets against the simulator's truth. `trueStates`: the frames
 *  carry the simulator's states; otherwise the calibrator's own classification, whose ids are
 *  mapped to the simulator's by majority. */
PerStateResult perStateOffsets(bool trueStates)
{
    DriveSpec d;
    d.frameRate_Hz = 50;
    sim::Scenario sc = calibtest::scenario(d);
    sc.impairments.antennaJumps = true;
    sc.impairments.jumpStates = 3;
    sc.impairments.jumpStep_s = 3e-9;
    sc.impairments.jumpRate_Hz = 0.1;
    sc.impairments.jumpStatePhase = true;
    sim::Simulator simulator(sc);
    PreprocessOptions po = calibrationPreprocessOptions();
    po.trackChainStates = true;
    FramePreparer prep(calibtest::arrayOf(d), po);
    PhaseCalibrator cal(calibtest::arrayOf(d));
    std::set<std::pair<unsigned, int>> visited;
    std::map<std::pair<unsigned, int>, std::map<int, size_t>> votes;  // (chain, id) → truth
    calibtest::driveFrames(
        simulator, prep, false,
        [&](const CalibrationFrame& f, const sim::FrameTruth& t)
        {
            CalibrationFrame g = f;
            for (unsigned i = 0; i < g.nRx; ++i)
            {
                visited.insert({i, t.packet.jumpState[i]});
                votes[{i, g.chainState[i]}][t.packet.jumpState[i]]++;
                if (trueStates) g.chainState[i] = t.packet.jumpState[i];
            }
            cal.add(g);
        });
    const auto res = cal.solve(cal.channels().at(0));
    const PhaseCalibration& c = res.calibration;
    const auto& hw = simulator.hardware();
    const Chanspec cs = c.chanspec;
    const double fc = cs.centerFrequencyHz();
    PerStateResult r;
    r.visited = visited.size();
    double acc = 0;
    size_t n = 0;
    for (const auto& st : c.chainStates)
    {
        ++r.states;
        int state = st.state;
        if (!trueStates)
        {
            const auto& v = votes.at({st.antenna, st.state});
            state = std::max_element(
                        v.begin(), v.end(), [](auto& a, auto& b) { return a.second < b.second; })
                        ->first;
        }
        const double tau = hw.jumpStateDelay_s(uint8_t(state));
        const double psi = hw.jumpStatePhase_rad(st.antenna, uint8_t(state));
        for (size_t j = 0; j < c.subcarriers.size(); ++j)
        {
            const int k = c.subcarriers[j];
            const double removed = c.phases_rad[st.antenna][j] + st.deltaPhase_rad -
                                   2 * M_PI * kSubcarrierSpacingHz * st.deltaDelay_s * k;
            const double truth = hw.chain(cs, st.antenna).phase_rad(k, cs.nfft()) -
                                 hw.chain(cs, 0).phase_rad(k, cs.nfft()) -
                                 2 * M_PI * std::fmod((fc + k * kSubcarrierSpacingHz) * tau, 1.0) +
                                 psi;
            const double e = wrapAngle(removed - truth);
            acc += e * e;
            ++n;
        }
    }
    r.rms_deg = std::sqrt(acc / double(std::max<size_t>(n, 1))) * 180 / M_PI;
    return r;
}
}  // namespace

// Issue 21's target: per-state offsets within 2° RMS of the truth. Measured: 0.51° with the
// simulator's states, 1.46° with the calibrator's own classification (what wifi-calibrate does).
TEST(CalibSim, PerStateOffsetsFromADriveWithJumps)
{
    const auto r = perStateOffsets(true);
    std::cout << "per-state offsets (true states): " << r.states << " states, RMS error "
              << r.rms_deg << " deg\n";
    ASSERT_GE(r.visited, 6u) << "the drive should visit several states per chain";
    EXPECT_EQ(r.states + 0, r.visited - 1) << "every visited state of chains 1-3";
    EXPECT_LT(r.rms_deg, 2.0);
}

TEST(CalibSim, PerStateOffsetsWithTheCalibratorsOwnStates)
{
    const auto r = perStateOffsets(false);
    std::cout << "per-state offsets (classified states): " << r.states << " states, RMS error "
              << r.rms_deg << " deg\n";
    ASSERT_GE(r.visited, 6u);
    EXPECT_EQ(r.states + 0, r.visited - 1) << "every visited state of chains 1-3, no spurious one";
    EXPECT_LT(r.rms_deg, 2.0);
}
