/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-calibrate --static-splitter from several captures, each feeding some of the chains
 * (issue 54.3): synthetic captures whose unfed chains hear the transmitter over a multipath
 * channel of their own (as real ones do), the merged file against the simulator's truth, the
 * refusals; and the muTrack splitter captures against the per-pair phases of their README. */
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/calib/SplitterCalibration.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "CalibTestSupport.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
const std::string kBin = MRPT_WIFI_BIN_DIR;

using Run = mrpt_wifi::test::SeparateOutputs;
Run run(const std::string& command)
{
    return mrpt_wifi::test::runSeparately(command);
}

constexpr double kLeakDelays_s[3] = {0.0, 35e-9, 80e-9};
const std::complex<double> kLeakGains[3] = {
    {0.7, 0.0}, std::polar(0.45, 1.2), std::polar(0.3, -2.1)};

/** What a chain the splitter does not feed receives: the transmitter over the air, through a
 *  static multipath channel of its own (coherent from frame to frame, not flat across the
 *  band; each element's paths a little longer or shorter). */
std::complex<float> leak(unsigned element, double f_Hz)
{
    std::complex<double> h{0, 0};
    for (int p = 0; p < 3; ++p)
        h += kLeakGains[p] * std::polar(
                                 1.0, -2 * M_PI * f_Hz * kLeakDelays_s[p] * (1 + 0.3 * element) +
                                          0.7 * element * p);
    return std::complex<float>(h);
}

/** A static splitter recording on channel 6 / 20 MHz whose chains jump among real-sized
 *  states (−20.9, −9, +4.1, +16 ns, each with its own phase). */
sim::Scenario splitterScenario()
{
    calibtest::DriveSpec d;
    d.splitter = true;
    d.motion = "static";
    d.multipath = false;
    d.channel = "6/20";
    d.duration_s = 16;
    d.snr_dB = 30;
    sim::Scenario sc = calibtest::scenario(d);
    sc.impairments.rippleAmplitude_rad = 1 * M_PI / 180;  // real chains: ~0.4° (muTrack)
    sc.impairments.antennaJumps = true;
    sc.impairments.jumpStateDelays_s = {-20.9e-9, -9.0e-9, 4.1e-9, 16.0e-9};
    sc.impairments.jumpStates = 4;
    sc.impairments.jumpRate_Hz = 0.4;
    sc.impairments.jumpStatePhase = true;
    return sc;
}

/** Writes the frames of [from, to) s as a capture feeding `fed` elements (the others get
 *  leak()), element `rotated` turned by `rotation_rad` (a changed cable). */
void writeCapture(
    const sim::Scenario& sc, double from_s, double to_s, const std::vector<unsigned>& fed,
    const std::string& path, unsigned rotated = 0, double rotation_rad = 0)
{
    sim::Simulator s(sc);
    s.setOdometryEnabled(false);
    mrpt::io::CFileGZOutputStream f(path);
    auto ar = mrpt::serialization::archiveFrom(f);
    sim::SimEvent ev;
    double t0 = -1;
    while (s.next(ev))
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        CObservationWiFiCSI& obs = *ev.csi;
        const double t = mrpt::Clock::toDouble(obs.timestamp);
        if (t0 < 0) t0 = t;
        if (t - t0 < from_s || t - t0 >= to_s) continue;
        const unsigned nfft = obs.nfft();
        for (unsigned e = 0; e < obs.nRx; ++e)
        {
            const bool isFed = std::find(fed.begin(), fed.end(), e) != fed.end();
            for (unsigned m = 0; m < obs.nTx; ++m)
                for (unsigned b = 0; b < nfft; ++b)
                {
                    auto& h = obs.pair(m, e)[b];
                    // The leak replaces the chain's share of the splitter's signal by the
                    // reference chain's signal through the air (chain e's own response kept).
                    if (!isFed)
                        h = h *
                            leak(e, subcarrierFrequencyHz(obs.chanspec, binToSubcarrier(b, nfft)));
                    if (e == rotated) h *= std::complex<float>(std::polar(1.0, rotation_rad));
                }
        }
        ar << obs;
    }
}

/** The array of the simulated splitter recording (4 elements, element i = core i). */
std::string writeArray(const std::string& dir)
{
    const std::string path = dir + "/splitter.yaml";
    std::ofstream(path) << "name: splitter\nelements:\n  - [0, 0]\n  - [0, 1.0e-6]\n"
                           "  - [0, 2.0e-6]\n  - [0, 3.0e-6]\n";
    return path;
}

/** RMS [deg] of the file's phases against the simulator's chains in the file's reference
 *  state of each chain (the one with no delta), relative to chain 0. */
double rmsAgainstTruth(const PhaseCalibration& c, const sim::Simulator& simulator)
{
    const auto& hw = simulator.hardware();
    double acc = 0;
    size_t n = 0;
    for (unsigned e = 1; e < c.antennas(); ++e)
    {
        const ChainStateCalibration* ref = nullptr;
        for (const auto& st : c.chainStates)
            if (st.antenna == e && st.deltaDelay_s == 0 && st.deltaPhase_rad == 0) ref = &st;
        if (!ref) return 1e9;
        uint8_t state = 0;  // the simulator's state nearest to the reference's delay
        for (uint8_t s = 1; s < hw.spec().jumpStates; ++s)
            if (std::abs(hw.jumpStateDelay_s(s) - ref->delay_s) <
                std::abs(hw.jumpStateDelay_s(state) - ref->delay_s))
                state = s;
        for (size_t j = 0; j < c.subcarriers.size(); ++j)
        {
            const int k = c.subcarriers[j];
            const double f = subcarrierFrequencyHz(c.chanspec, k);
            const double truth = hw.chain(c.chanspec, e).phase_rad(k, c.chanspec.nfft()) -
                                 hw.chain(c.chanspec, 0).phase_rad(k, c.chanspec.nfft()) -
                                 2 * M_PI * std::fmod(f * hw.jumpStateDelay_s(state), 1.0) +
                                 hw.jumpStatePhase_rad(e, state);
            const double d = wrapAngle(c.phases_rad[e][j] - truth);
            acc += d * d;
            ++n;
        }
    }
    return std::sqrt(acc / double(n)) * 180 / M_PI;
}

class SplitterCalib : public ::testing::Test
{
protected:
    static void SetUpTestSuite()
    {
        dir_ = test::tempPath() + "_splitter";
        mrpt::system::createDirectory(dir_);
        array_ = writeArray(dir_);
        const sim::Scenario sc = splitterScenario();
        // Capture A feeds chains 0, 1, 2 in the first 8 s; capture B chains 0 and 3 after.
        writeCapture(sc, 0, 8, {0, 1, 2}, dir_ + "/a.rawlog");
        writeCapture(sc, 8, 16, {0, 3}, dir_ + "/b.rawlog");
        // A again, with chain 1's cable changed (30°), and a capture that feeds only 1 and 2.
        writeCapture(sc, 0, 8, {0, 1, 2}, dir_ + "/a_rotated.rawlog", 1, 30 * M_PI / 180);
        writeCapture(sc, 0, 8, {1, 2}, dir_ + "/no_reference.rawlog");
    }
    static std::string dir_, array_;
    std::string cal() const
    {
        return kBin + "/wifi-calibrate -q --static-splitter --array " + array_ + " ";
    }
};
std::string SplitterCalib::dir_, SplitterCalib::array_;
}  // namespace

TEST_F(SplitterCalib, TwoCapturesFeedingSomeChainsMakeOneCalibration)
{
    const std::string out = dir_ + "/out";
    const auto r = run(cal() + dir_ + "/a.rawlog " + dir_ + "/b.rawlog -o " + out);
    ASSERT_EQ(r.rc, 0) << r.out << r.err;
    // Each capture's fed chains, detected from the CSI.
    EXPECT_NE(r.out.find("fed chains       : cores 0, 1, 2 (detected"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("fed chains       : cores 0, 3 (detected"), std::string::npos) << r.out;
    const PhaseCalibration c = PhaseCalibration::fromYamlFile(
        PhaseCalibration::pathFor(out, "splitter", Chanspec::fromString("6/20")));
    ASSERT_EQ(c.antennas(), 4u);
    // The jump states (one 80 MHz sample apart) learnt for every chain, each in the file.
    for (unsigned e = 1; e < 4; ++e)
    {
        size_t states = 0;
        for (const auto& st : c.chainStates) states += st.antenna == e;
        EXPECT_GE(states, 2u) << "chain " << e << "\n" << r.out;
    }
    EXPECT_NEAR(c.chainStateTolerance_s, 4e-9, 1e-12);
    const sim::Simulator simulator(splitterScenario());
    const double rms = rmsAgainstTruth(c, simulator);
    std::cout << "merged splitter calibration: " << rms << " deg RMS against the truth\n";
    EXPECT_LT(rms, 1.5);

    // The same with the fed chains given: the same file.
    const std::string out2 = dir_ + "/out2";
    const auto r2 =
        run(cal() + dir_ + "/a.rawlog " + dir_ + "/b.rawlog --fed-cores 0,1,2 --fed-cores 0,3 -o " +
            out2);
    ASSERT_EQ(r2.rc, 0) << r2.out << r2.err;
    EXPECT_NE(r2.out.find("cores 0, 3 (--fed-cores"), std::string::npos) << r2.out;
    const PhaseCalibration c2 = PhaseCalibration::fromYamlFile(
        PhaseCalibration::pathFor(out2, "splitter", Chanspec::fromString("6/20")));
    EXPECT_EQ(c2.phases_rad, c.phases_rad);
}

TEST_F(SplitterCalib, RefusesAChainNoCaptureFeeds)
{
    const auto r = run(cal() + dir_ + "/a.rawlog -o " + dir_ + "/out_a");
    EXPECT_EQ(r.rc, 1) << r.out << r.err;
    EXPECT_NE(r.err.find("element 3 (core 3) is fed by no capture"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("a.rawlog: elements 0, 1, 2"), std::string::npos) << r.err;
    EXPECT_FALSE(mrpt::system::fileExists(dir_ + "/out_a/splitter/ch6_20mhz.yaml"));
}

TEST_F(SplitterCalib, RefusesCapturesThatDisagreeOnAChain)
{
    const auto r =
        run(cal() + dir_ + "/a.rawlog " + dir_ + "/a_rotated.rawlog " + dir_ + "/b.rawlog -o " +
            dir_ + "/out_rot");
    EXPECT_EQ(r.rc, 1) << r.out << r.err;
    EXPECT_NE(r.err.find("disagree on element 1 (core 1) by 30."), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("a_rotated.rawlog"), std::string::npos) << r.err;
}

TEST_F(SplitterCalib, RefusesACaptureWithoutTheReferenceChain)
{
    // Detected: nothing is flat against chain 0.
    const auto r =
        run(cal() + dir_ + "/no_reference.rawlog " + dir_ + "/b.rawlog -o " + dir_ + "/out_nr");
    EXPECT_EQ(r.rc, 1) << r.out << r.err;
    EXPECT_NE(
        r.err.find("no_reference.rawlog': no chain is fed together with core 0"), std::string::npos)
        << r.err;
    // Given: the list must hold core 0.
    const auto r2 =
        run(cal() + dir_ + "/no_reference.rawlog " + dir_ +
            "/b.rawlog --fed-cores 1,2 --fed-cores " + "0,3 -o " + dir_ + "/out_nr2");
    EXPECT_EQ(r2.rc, 1) << r2.out << r2.err;
    EXPECT_NE(r2.err.find("must include core 0"), std::string::npos) << r2.err;
    // Bad option use.
    const auto r3 =
        run(cal() + dir_ + "/a.rawlog " + dir_ + "/b.rawlog --fed-cores 0,1 -o " + dir_ + "/x");
    EXPECT_EQ(r3.rc, 1) << r3.err;
    EXPECT_NE(r3.err.find("once per input"), std::string::npos) << r3.err;
    const auto r4 =
        run(kBin + "/wifi-calibrate -q --array " + array_ + " --tx-position 0 0 " + dir_ +
            "/a.rawlog " + dir_ + "/b.rawlog -o " + dir_ + "/x");
    EXPECT_EQ(r4.rc, 1) << r4.err;
    EXPECT_NE(r4.err.find("several inputs are for --static-splitter"), std::string::npos) << r4.err;
}

TEST(SplitterCalibReal, MuTrackTwoCaptureCalibrationMatchesTheReadme)
{
    // Issue 54.3: the muTrack splitter captures (R1R2: cores 0+1, R1R3: cores 0+3, core 2 off)
    // of each access point give one calibration whose phases at subcarrier −2 equal the
    // per-pair phases the data's README lists (core 1 − core 0, core 3 − core 0) within 1°.
    const std::string shared = test::sharedDir();
    const std::string calib = shared + "/data/mutrack/calib/spotFi_fastcalib_20M_2G_";
    if (shared.empty() || !mrpt::system::fileExists(calib + "R1R2_AP2_tr1.pcap"))
        GTEST_SKIP() << "muTrack splitter captures not found (../shared absent)";
    const std::map<int, std::pair<double, double>> readme = {
        {2, {2.8312, 2.7790}}, {3, {-2.6780, 0.5276}}, {5, {3.1189, 3.0228}}};
    const std::string dir = test::tempPath() + "_mutrack";
    mrpt::system::createDirectory(dir);
    for (const auto& [ap, phases] : readme)
    {
        std::string inputs;
        for (const std::string wiring : {"R1R2", "R1R3"})
        {
            const std::string rawlog = dir + "/" + wiring + "_AP" + std::to_string(ap) + ".rawlog";
            const auto imp =
                run(kBin + "/csi-import -q " + calib + wiring + "_AP" + std::to_string(ap) +
                    "_tr1.pcap " + rawlog);
            ASSERT_EQ(imp.rc, 0) << imp.err;
            inputs += " " + rawlog;
        }
        const std::string out = dir + "/AP" + std::to_string(ap);
        const auto r =
            run(kBin + "/wifi-calibrate -q --static-splitter --array rt-ac86u-3core-57mm" + inputs +
                " -o " + out);
        ASSERT_EQ(r.rc, 0) << r.out << r.err;
        EXPECT_NE(r.out.find("fed chains       : cores 0, 1 (detected"), std::string::npos)
            << r.out;
        EXPECT_NE(r.out.find("fed chains       : cores 0, 3 (detected"), std::string::npos)
            << r.out;
        const PhaseCalibration c = PhaseCalibration::fromYamlFile(
            PhaseCalibration::pathFor(out, "rt-ac86u-3core-57mm", Chanspec::fromString("6/20")));
        ASSERT_EQ(c.antennas(), 3u);
        // Their states differ by a delay alone (sample slips): by default not in the file, so
        // over-the-air frames, whose delays can't be matched to them, keep their bearings.
        EXPECT_NE(r.out.find("differ by a delay alone"), std::string::npos) << r.out;
        EXPECT_TRUE(c.chainStates.empty());
        EXPECT_TRUE(c.chainStatesDelayOnly);
        const auto on =
            run(kBin +
                "/wifi-calibrate -q --static-splitter --chain-states on --array "
                "rt-ac86u-3core-57mm" +
                inputs + " -o " + out + "_states");
        ASSERT_EQ(on.rc, 0) << on.out << on.err;
        const PhaseCalibration withStates =
            PhaseCalibration::fromYamlFile(PhaseCalibration::pathFor(
                out + "_states", "rt-ac86u-3core-57mm", Chanspec::fromString("6/20")));
        // The file with its states holds the phases as measured in each chain's reference state:
        // at k = -2 they are the README's.
        const size_t j = size_t(
            std::find(c.subcarriers.begin(), c.subcarriers.end(), -2) - c.subcarriers.begin());
        ASSERT_LT(j, c.subcarriers.size());
        const double e1 = std::remainder(withStates.phases_rad[1][j] - phases.first, 2 * M_PI);
        const double e3 = std::remainder(withStates.phases_rad[2][j] - phases.second, 2 * M_PI);
        std::cout << "AP" << ap << ": core 1 " << withStates.phases_rad[1][j] << " rad ("
                  << e1 * 180 / M_PI << " deg from the README), core 3 "
                  << withStates.phases_rad[2][j] << " rad (" << e3 * 180 / M_PI << " deg)\n";
        EXPECT_LT(std::abs(e1) * 180 / M_PI, 1.0) << "AP" << ap << " core 1";
        EXPECT_LT(std::abs(e3) * 180 / M_PI, 1.0) << "AP" << ap << " core 3";
        // The default file holds the same phases without the reference state's delay (what holds
        // in every state): the two differ by that delay's slope across the subcarriers alone.
        for (unsigned e = 1; e < 3; ++e)
        {
            const ChainStateCalibration* ref = nullptr;
            for (const auto& st : withStates.chainStates)
                if (st.antenna == e && st.deltaDelay_s == 0) ref = &st;
            ASSERT_NE(ref, nullptr) << "AP" << ap << " element " << e;
            for (size_t k = 0; k < c.subcarriers.size(); ++k)
                EXPECT_NEAR(
                    c.phases_rad[e][k],
                    withStates.phases_rad[e][k] +
                        2 * M_PI * kSubcarrierSpacingHz * c.subcarriers[k] * ref->delay_s,
                    1e-6)
                    << "AP" << ap << " element " << e << " k " << c.subcarriers[k];
        }
        // Every fed chain jumps among states one 80 MHz sample (12.5 ns) or a few apart.
        for (unsigned e = 1; e < 3; ++e)
        {
            std::vector<double> delays;
            for (const auto& st : withStates.chainStates)
            {
                if (st.antenna != e) continue;
                delays.push_back(st.delay_s);
                EXPECT_LT(std::abs(st.deltaPhase_rad) * 180 / M_PI, 1.0) << "AP" << ap;
            }
            ASSERT_GE(delays.size(), 2u) << "AP" << ap << " element " << e << "\n" << r.out;
            std::sort(delays.begin(), delays.end());
            for (size_t i = 1; i < delays.size(); ++i)
            {
                const double steps = (delays[i] - delays[i - 1]) / 12.5e-9;
                EXPECT_GE(std::round(steps), 1.0) << "AP" << ap << " element " << e;
                EXPECT_LT(std::abs(steps - std::round(steps)) * 12.5, 2.0)
                    << "AP" << ap << " element " << e << ": states " << delays[i - 1] * 1e9
                    << " and " << delays[i] * 1e9 << " ns\n"
                    << r.out;
            }
        }
    }
}
