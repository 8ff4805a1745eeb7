/* mrpt_wifi — wifi-localize end to end: the emulator (CSI + odometry stream on 127.0.0.1),
 * the sensors run in-process from an .ini via the plugin, MRPT's particle filter live; errors
 * against the emulator's ground truth (STATE_DIR/truth), written on the receiver's clock. */
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/localization/DeviceMapper.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "EmulatorProcess.h"
#include "SshdFixture.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

namespace
{
const std::string kShare = test::sourceDir() + "/share";

/** share/localization/wifi-localize-emulator.ini with [section] key values replaced or added
 *  (absolute paths, test ports) and sections dropped. */
std::string deriveIni(
    const std::map<std::string, std::string>& keys, const std::set<std::string>& dropSections,
    const std::string& out)
{
    std::istringstream in(test::readFile(kShare + "/localization/wifi-localize-emulator.ini"));
    std::ostringstream o;
    std::string section;
    std::set<std::string> written;
    const auto addMissing = [&]
    {
        for (const auto& [sectionKey, value] : keys)
            if (sectionKey.rfind(section + "/", 0) == 0 && written.insert(sectionKey).second)
                o << sectionKey.substr(section.size() + 1) << " = " << value << "\n";
    };
    for (std::string line; std::getline(in, line);)
    {
        if (!line.empty() && line[0] == '[')
        {
            if (!dropSections.count(section)) addMissing();
            section = line.substr(1, line.find(']') - 1);
        }
        if (dropSections.count(section)) continue;
        const auto eq = line.find('=');
        if (eq != std::string::npos && line[0] != ';')
        {
            std::string key = line.substr(0, eq);
            key.erase(key.find_last_not_of(" \t") + 1);
            if (auto it = keys.find(section + "/" + key); it != keys.end())
            {
                o << key << " = " << it->second << "\n";
                written.insert(it->first);
                continue;
            }
        }
        o << line << "\n";
    }
    if (!dropSections.count(section)) addMissing();
    std::ofstream(out) << o.str();
    return out;
}

/** The emulated APs' transmit-chain calibration: like real ones, every AP's chains have their
 *  own phases, so AoD needs them calibrated. A 40 s drive of the scenario the emulator plays
 *  (kidnapped.yaml, seed 7) and wifi-calibrate --transmit-chains (--force: two APs are seen
 *  from fewer distinct bearings than it asks for). Made once per build tree (it is
 *  deterministic); tests running in parallel each make their own and the first rename wins. */
std::string apCalibration()
{
    const std::string dir = test::binDir() + "/../test-cache/kidnapped-ap-calibration";
    if (std::filesystem::is_directory(dir)) return dir;
    test::TempDir tmp;
    const auto sim = test::run(
        test::binDir() + "/wifi-sim " + kShare + "/scenarios/kidnapped.yaml " +
        tmp.file("drive.rawlog") + " --seed 7 -d 40 -q -t " + tmp.file("truth"));
    EXPECT_EQ(sim.exitCode, 0) << sim.output;
    const auto cal = test::run(
        test::binDir() + "/wifi-calibrate " + tmp.file("drive.rawlog") + " --array " + kShare +
        "/arrays/rt-ac86u.yaml --transmitters " + tmp.file("truth/transmitters.yaml") +
        " --poses " + tmp.file("truth/trajectory_tum.txt") +
        " --transmit-chains --force -q --out " + tmp.file("calib"));
    EXPECT_EQ(cal.exitCode, 0) << cal.output;
    std::filesystem::create_directories(std::filesystem::path(dir).parent_path());
    std::error_code ec;  // another test may have renamed its copy first: same content
    std::filesystem::rename(tmp.file("calib"), dir, ec);
    return dir;
}

std::map<std::string, std::string> baseKeys(uint16_t csiPort, uint16_t odoPort)
{
    return {
        {"wifi-localize/bearing_calibration", apCalibration()},
        {"WIFI_CSI/udp_port", std::to_string(csiPort)},
        {"ODOMETRY/udp_port", std::to_string(odoPort)},
        {"wifi-localize/bearing_array", kShare + "/arrays/rt-ac86u.yaml"},
        {"wifi-localize/bearing_tx_arrays", kShare + "/arrays/ap-linear-4.yaml"},
        {"MetricMap_wifiBearingMap_00_creationOpts/transmitters_file",
         kShare + "/localization/kidnapped-aps.yaml"},
        // fewer particles than the shipped file: the test shares the machine
        {"LocalizationExperiment/particles_count", "1500"},
        {"KLD_options/KLD_minSampleSize", "1500"},
        {"KLD_options/KLD_maxSampleSize", "1500"}};
}

/** The emulator's ground truth (STATE_DIR/truth/trajectory_tum.txt): already on the receiver's
 *  clock, the one wifi-localize stamps its estimates with, so compared without any shift. */
Trajectory2D emulatorTruth(const std::string& stateDir)
{
    return Trajectory2D::fromTumFile(stateDir + "/truth/trajectory_tum.txt");
}

struct Errors
{
    std::vector<double> afterWarmup;  // position errors [m] from `warmup` s on
    size_t estimates = 0;
    double span = 0;  // s from first to last estimate
};

Errors errorsOf(const Trajectory2D& est, const Trajectory2D& gt, double warmup)
{
    Errors e;
    e.estimates = est.size();
    if (est.empty()) return e;
    e.span = est.t.back() - est.t.front();
    for (size_t i = 0; i < est.size(); ++i)
    {
        mrpt::math::TPose2D g;
        if (est.t[i] - est.t.front() < warmup || !gt.interpolate(est.t[i], g, 0.5)) continue;
        e.afterWarmup.push_back(std::hypot(est.poses[i].x - g.x, est.poses[i].y - g.y));
    }
    return e;
}

double median(std::vector<double> v)
{
    if (v.empty()) return NAN;
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}

struct LiveRun
{
    test::CommandResult result;
    Trajectory2D estimate, truth;
};

/** The emulator (kidnapped.yaml, preconfigured, optional odometry stream) and wifi-localize
 *  for `seconds`; `keys`: more `.ini` keys ("SECTION/key" → value, as deriveIni). */
LiveRun runLive(
    const test::TempDir& tmp, double seconds, bool odometry, const std::string& extraArgs = {},
    const std::string& wrapper = {}, const std::map<std::string, std::string>& keys = {})
{
    const uint16_t csiPort = test::freeLoopbackPort(SOCK_DGRAM);
    uint16_t odoPort = test::freeLoopbackPort(SOCK_DGRAM);
    if (odoPort == csiPort) odoPort = uint16_t(csiPort + 1);
    std::vector<std::string> emuArgs = {
        "--scenario", kShare + "/scenarios/kidnapped.yaml", "--preconfigured", "155/80"};
    if (odometry) emuArgs.insert(emuArgs.end(), {"--odometry-port", std::to_string(odoPort)});
    test::EmulatorProcess emu(emuArgs, csiPort, seconds + 30);
    EXPECT_TRUE(emu.ready()) << emu.log();
    auto allKeys = baseKeys(csiPort, odoPort);
    for (const auto& [k, v] : keys) allKeys[k] = v;
    const auto ini = deriveIni(
        allKeys, odometry ? std::set<std::string>{} : std::set<std::string>{"ODOMETRY"},
        tmp.file("live.ini"));
    LiveRun r;
    r.result = test::run(
        "cd " + tmp.path().string() + " && timeout " + std::to_string(int(seconds + 60)) + " " +
        wrapper + " " + test::binDir() + "/wifi-localize -p " + test::libDir() +
        "/libmrpt_wifi_sensor.so " + ini + " -q -o out -d " + std::to_string(seconds) + " " +
        extraArgs);
    emu.stop();
    if (r.result.exitCode == 0)
    {
        r.estimate = Trajectory2D::fromTumFile(tmp.file("out/estimate_tum.txt"));
        r.truth = emulatorTruth(emu.stateDir());
    }
    return r;
}

/** The reported uncertainty covers the error: one row of estimate_cov.csv per pose of the TUM
 *  output, and after a 5 s warm-up the true position inside the estimate's 95 % ellipse in at
 *  least 90 % of the poses. Otherwise, second by second: what was inside, the error, σ and how
 *  far the reported estimate was from the filter's mean (pf_estimate_tum.txt), and the app's
 *  summary: a failure under a busy machine must say where it went wrong. */
void expectUncertaintyCoversTheError(const test::TempDir& tmp, const LiveRun& r)
{
    std::ifstream covCsv(tmp.file("out/estimate_cov.csv"));
    std::string line;
    ASSERT_TRUE(std::getline(covCsv, line));
    EXPECT_EQ(line.rfind("t,x_m,y_m,phi_deg,std_x_m,std_y_m,corr_xy,std_phi_deg", 0), 0u) << line;
    // The filter's own mean, one per pose output.
    const auto pfMean = Trajectory2D::fromTumFile(tmp.file("out/pf_estimate_tum.txt"));
    EXPECT_EQ(pfMean.t, r.estimate.t);
    struct Second
    {
        size_t judged = 0, inside = 0;
        std::vector<double> error, sigma, fromPfMean;
    };
    std::map<int, Second> bySecond;
    size_t rows = 0, judged = 0, inside = 0;
    for (; std::getline(covCsv, line); ++rows)
    {
        std::vector<double> v;
        std::stringstream ss(line);
        for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
        ASSERT_EQ(v.size(), 12u) << line;
        ASSERT_LT(rows, r.estimate.size());
        EXPECT_DOUBLE_EQ(v[0], r.estimate.t[rows]);
        // The reported σ includes the particles' spread about the reported pose: their own
        // and how far the smoother's estimate is from their mean (σ cells rounded to 1e-5 m).
        if (rows < pfMean.size())
        {
            const auto& e = r.estimate.poses[rows];
            EXPECT_GE(v[4], std::hypot(v[8], e.x - pfMean.poses[rows].x) - 2e-5) << line;
            EXPECT_GE(v[5], std::hypot(v[9], e.y - pfMean.poses[rows].y) - 2e-5) << line;
        }
        mrpt::math::TPose2D g;
        if (v[0] - r.estimate.t.front() < 5.0 || !r.truth.interpolate(v[0], g, 0.5)) continue;
        const double xy = v[6] * v[4] * v[5];
        const bool in =
            mahalanobis2(v[4] * v[4], xy, v[5] * v[5], v[1] - g.x, v[2] - g.y) <= kChi2TwoDof95;
        ++judged;
        inside += in;
        auto& sec = bySecond[int(v[0] - r.estimate.t.front())];
        ++sec.judged;
        sec.inside += in;
        sec.error.push_back(std::hypot(v[1] - g.x, v[2] - g.y));
        sec.sigma.push_back(std::max(v[4], v[5]));
        if (rows < pfMean.size())
            sec.fromPfMean.push_back(
                std::hypot(v[1] - pfMean.poses[rows].x, v[2] - pfMean.poses[rows].y));
    }
    EXPECT_EQ(rows, r.estimate.size());
    ASSERT_GT(judged, 20u);
    std::ostringstream perSecond;
    perSecond << "s: inside/poses, median error, median sigma (larger axis), median distance "
                 "from the PF mean [m]\n";
    for (const auto& [second, sec] : bySecond)
        perSecond << second << ": " << sec.inside << "/" << sec.judged << ", " << median(sec.error)
                  << ", " << median(sec.sigma) << ", " << median(sec.fromPfMean) << "\n";
    EXPECT_GE(double(inside) / double(judged), 0.9) << inside << " of " << judged << "\n"
                                                    << perSecond.str() << r.result.output;
}
}  // namespace

TEST(WifiLocalize, LocalizesTheKidnappedRobotLiveFromTheEmulator)
{
    test::TempDir tmp;
    const auto r = runLive(tmp, 14, true, "-r seen.rawlog");
    ASSERT_EQ(r.result.exitCode, 0) << r.result.output;
    EXPECT_NE(r.result.output.find("odometry       : yes"), std::string::npos) << r.result.output;
    // wifi-localize's own bearing chain gets the odometry, as csi-bearings does offline.
    EXPECT_NE(r.result.output.find("bearing chain  : odometry given"), std::string::npos)
        << r.result.output;
    const auto e = errorsOf(r.estimate, r.truth, 5.0);
    ASSERT_GT(e.afterWarmup.size(), 20u) << r.result.output;
    // Kidnapped: the filter starts uniform over the room; after 5 s of bearings it must be
    // where the robot is (the issue's target is a median <= 0.5 m after convergence).
    EXPECT_LE(median(e.afterWarmup), 0.5) << r.result.output;
    expectUncertaintyCoversTheError(tmp, r);
    // With odometry the window smoother refines the estimate live, as offline.
    std::smatch sm;
    const std::regex smoother("window smoother: .*: ([0-9]+) of ([0-9]+) solves used");
    ASSERT_TRUE(std::regex_search(r.result.output, sm, smoother)) << r.result.output;
    EXPECT_GT(std::stoul(sm[1]), 0u) << r.result.output;

    // The rawlog holds what the sensors delivered: CSI of 4 APs and the odometry stream.
    mrpt::io::CFileGZInputStream f(tmp.file("seen.rawlog"));
    auto arch = mrpt::serialization::archiveFrom(f);
    size_t csi = 0, odo = 0, csiInsideTruth = 0;
    for (;;)
    {
        mrpt::serialization::CSerializable::Ptr obj;
        try
        {
            arch >> obj;
        }
        catch (const std::exception&)
        {
            break;
        }
        const auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(obj);
        csi += bool(c);
        odo += bool(std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obj));
        // The emulator's truth is on the recording's clock: every CSI frame recorded falls
        // within it (no shift by unix_time_at_sim_zero). The emulator ran on after the run.
        if (c && !r.truth.empty() && mrpt::Clock::toDouble(c->timestamp) >= r.truth.t.front() &&
            mrpt::Clock::toDouble(c->timestamp) <= r.truth.t.back())
            ++csiInsideTruth;
    }
    EXPECT_EQ(csiInsideTruth, csi)
        << "truth " << std::fixed << r.truth.t.front() << " .. " << r.truth.t.back();
    // Every observation the sensors delivered is in the recording (the summary counts them; how
    // many arrive in 14 s depends on the machine's load, so no fixed number).
    std::smatch m;
    const std::regex delivered("observations   : ([0-9]+) CSI, ([0-9]+) odometry");
    ASSERT_TRUE(std::regex_search(r.result.output, m, delivered)) << r.result.output;
    EXPECT_GT(csi, 0u);
    EXPECT_GT(odo, 0u);
    EXPECT_EQ(csi, std::stoul(m[1]));
    EXPECT_EQ(odo, std::stoul(m[2]));
}

TEST(WifiLocalize, UsesTheCsiSensorsOwnLiveBearings)
{
    // The CSI sensor estimates the bearings itself (its bearing_* keys: AoD with the APs'
    // calibrated transmit chains, the same chain as [wifi-localize]'s own in the shipped .ini):
    // wifi-localize uses the sensor's `WIFI_CSI_AOA` observations and never estimates again on
    // that CSI (not even on the first frames, which arrive before their bearings), and they
    // localize the kidnapped robot as well.
    test::TempDir tmp;
    const auto r = runLive(
        tmp, 14, true, "-r seen.rawlog", {},
        {{"WIFI_CSI/bearing_algorithm", "aod"},
         {"WIFI_CSI/bearing_calibration", apCalibration()},
         {"WIFI_CSI/bearing_array", kShare + "/arrays/rt-ac86u.yaml"},
         {"WIFI_CSI/bearing_tx_arrays", kShare + "/arrays/ap-linear-4.yaml"}});
    ASSERT_EQ(r.result.exitCode, 0) << r.result.output;
    EXPECT_NE(
        r.result.output.find("(0 computed by wifi-localize, 1 sensor(s) with own bearings)"),
        std::string::npos)
        << r.result.output;
    // The sensor's chain got the odometry from wifi-localize, as csi-bearings' chain does.
    EXPECT_TRUE(std::regex_search(
        r.result.output,
        std::regex(R"(sensor chain   : \[WIFI_CSI\] [1-9][0-9]* odometry readings given)")))
        << r.result.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(r.result.output, m, std::regex("bearings used  : ([0-9]+)")))
        << r.result.output;
    EXPECT_GT(std::stoul(m[1]), 1000u) << r.result.output;  // ~4 x 100 per second
    // The summary names the shipped step cap and its catch-up.
    std::smatch steps;
    ASSERT_TRUE(std::regex_search(
        r.result.output, steps,
        std::regex(R"(filter steps   : ([0-9]+) \(up to 2 bearings per step, more when queued )"
                   R"(over 0.25 s\))")))
        << r.result.output;
    EXPECT_LE(std::stoul(steps[1]), std::stoul(m[1]));
    const auto e = errorsOf(r.estimate, r.truth, 5.0);
    ASSERT_GT(e.afterWarmup.size(), 20u) << r.result.output;
    EXPECT_LE(median(e.afterWarmup), 0.5) << r.result.output;
    expectUncertaintyCoversTheError(tmp, r);

    // What wifi-localize saw: the sensor's bearings, labelled after it, right after the CSI.
    mrpt::io::CFileGZInputStream f(tmp.file("seen.rawlog"));
    auto arch = mrpt::serialization::archiveFrom(f);
    size_t csi = 0, own = 0, other = 0;
    for (;;)
    {
        mrpt::serialization::CSerializable::Ptr obj;
        try
        {
            arch >> obj;
        }
        catch (const std::exception&)
        {
            break;
        }
        csi += bool(std::dynamic_pointer_cast<CObservationWiFiCSI>(obj));
        if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(obj))
            (b->sensorLabel == "WIFI_CSI_AOA" && b->algorithm == "aod" ? own : other)++;
    }
    EXPECT_GT(csi, 0u);       // how many in 14 s: the machine's load decides
    EXPECT_GT(own, csi / 2);  // AoA + AoD of (almost) every frame: the worker keeps up
    EXPECT_EQ(other, 0u);
}

TEST(WifiLocalize, RunsWithoutOdometry)
{
    test::TempDir tmp;
    const auto r = runLive(tmp, 14, false);
    ASSERT_EQ(r.result.exitCode, 0) << r.result.output;
    // The offline filter's [UnknownMotion] model, bounded by the room (issue 19.2).
    EXPECT_NE(
        r.result.output.find("none (unknown motion model: constant velocity + random walk"),
        std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find(", 0 estimates outside it"), std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find("bearing chain  : no odometry"), std::string::npos)
        << r.result.output;
    // Without odometry the window smoother fits a track (without_odometry = true), so it does
    // not say it needs odometry, and the map weighs the bearings.
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        r.result.output, m, std::regex("window smoother: .*: ([0-9]+) of ([0-9]+) solves used")))
        << r.result.output;
    EXPECT_GT(std::stoul(m[2]), 0u) << r.result.output;
    EXPECT_EQ(r.result.output.find("needs odometry"), std::string::npos) << r.result.output;
    ASSERT_TRUE(std::regex_search(
        r.result.output, m, std::regex("with an angle the map weighs: ([0-9]+)\\)")))
        << r.result.output;
    EXPECT_GT(std::stoul(m[1]), 0u) << r.result.output;
    EXPECT_EQ(r.result.output.find("WARNING"), std::string::npos) << r.result.output;
    const auto e = errorsOf(r.estimate, r.truth, 5.0);
    ASSERT_GT(e.afterWarmup.size(), 20u) << r.result.output;
    EXPECT_LE(median(e.afterWarmup), 0.8) << r.result.output;
    // The σ is about the reported pose, the smoother's track, not the particles' mean.
    expectUncertaintyCoversTheError(tmp, r);
}

TEST(WifiLocalize, WarnsWhenTheMapWeighsNoneOfTheBearings)
{
    // The shipped .ini's map weighs AoD only; its own chain without the APs' transmit array
    // gives AoA only, bearings the map ignores. The run ends with its summary written
    // (nothing recorded is lost), says why the estimate never moved, and is a failure: the
    // status of bearings the map cannot weigh, naming the calibration to make.
    test::TempDir tmp;
    const auto r = runLive(
        tmp, 4, false, {}, {},
        {{"wifi-localize/bearing_algorithm", "default"}, {"wifi-localize/bearing_tx_arrays", ""}});
    ASSERT_EQ(r.result.exitCode, 8) << r.result.output;
    EXPECT_NE(r.result.output.find("none with an angle the map weighs"), std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find("wifi-calibrate --transmit-chains"), std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find("with an angle the map weighs: 0)"), std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find("wifi-localize: warning: none of the "), std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find("(use_aoa = false, use_aod = true"), std::string::npos)
        << r.result.output;
    EXPECT_NE(
        test::readFile(tmp.file("out/summary.txt")).find("WARNING        : none of the"),
        std::string::npos);
}

TEST(WifiLocalize, ViewUnderXvfbShowsMapParticlesAndRays)
{
    if (test::run("command -v xvfb-run").exitCode != 0)
        GTEST_SKIP() << "xvfb-run not installed (scripts/install-deps.sh installs it)";
    test::TempDir tmp;
    const auto shot = tmp.file("view.png");
    const auto r = runLive(
        tmp, 8, true, "--view --screenshot " + shot, "xvfb-run -a -s '-screen 0 1280x800x24'");
    ASSERT_EQ(r.result.exitCode, 0) << r.result.output;
    mrpt::img::CImage img;
    ASSERT_TRUE(img.loadFromFile(shot)) << r.result.output;
    ASSERT_EQ(img.getWidth(), 1000u);
    ASSERT_EQ(img.getHeight(), 700u);
    // Not a blank picture: the orange bearing rays, the blue particles, the grid, the text.
    size_t orange = 0, blue = 0;
    std::set<uint32_t> colours;
    const auto rgb = img.colorImage();
    for (unsigned y = 0; y < img.getHeight(); ++y)
        for (unsigned x = 0; x < img.getWidth(); ++x)
        {
            const auto* p = rgb.ptr<uint8_t>(int(x), int(y));  // BGR
            const int b = p[0], g = p[1], rr = p[2];
            colours.insert(uint32_t(rr << 16 | g << 8 | b));
            orange += rr > 180 && g > 80 && g < 190 && b < 90;
            blue += b > 150 && rr < 120 && b > g + 30;
        }
    EXPECT_GT(orange, 1000u);
    EXPECT_GT(blue, 10u);
    EXPECT_GT(colours.size(), 100u);
}

TEST(WifiLocalize, ReplayingACaptureGivesTheOfflineEstimate)
{
    // One simulated drive as a tcpdump-style capture (CSI only, no odometry) and as a rawlog.
    test::TempDir tmp;
    const double seconds = 10;
    const auto sim = test::run(
        test::binDir() + "/wifi-sim " + kShare + "/scenarios/kidnapped.yaml " +
        tmp.file("sim.rawlog") + " --pcap " + tmp.file("sim.pcap") + " -q -d " +
        std::to_string(int(seconds)) + " -t " + tmp.file("truth"));
    ASSERT_EQ(sim.exitCode, 0) << sim.output;

    // Offline: csi-bearings (AoD, as wifi-localize's own chain in the .ini) and
    // wifi-pf-localization, bearings only (the capture has no odometry either): both filters
    // use the .ini's [UnknownMotion].
    const auto bearings = test::run(
        test::binDir() + "/csi-bearings " + tmp.file("sim.rawlog") + " " + tmp.file("b.rawlog") +
        " --algo aod --tx-array " + kShare + "/arrays/ap-linear-4.yaml --calib " + apCalibration() +
        " --csv " + tmp.file("b.csv") + " -q");
    ASSERT_EQ(bearings.exitCode, 0) << bearings.output;
    std::filesystem::remove(tmp.file("sim.rawlog"));
    const auto offIni = tmp.file("off.ini");
    {
        std::istringstream in(test::readFile(kShare + "/localization/pf-localization-wifi.ini"));
        std::ofstream o(offIni);
        for (std::string line; std::getline(in, line);)
            o << (line.rfind("use_aoa", 0) == 0 ? std::string("use_aoa = false") : line) << "\n";
    }
    const auto off = test::run(
        test::binDir() + "/wifi-pf-localization " + offIni + " -m " + kShare +
        "/localization/kidnapped-aps.yaml -b " + tmp.file("b.csv") +
        " --sensor-pose 0.1 0 0.4 0 0 0 -n 1500 -q --no-plots -o " + tmp.file("off"));
    ASSERT_EQ(off.exitCode, 0) << off.output;

    // Live: the capture replayed by CWiFiCSISensor (source = pcap) inside wifi-localize.
    auto keys = baseKeys(5500, 5501);
    keys["WIFI_CSI/source"] = "pcap\npcap_file = " + tmp.file("sim.pcap");
    keys["WIFI_CSI/router_address"] = "";
    const auto ini = deriveIni(keys, {"ODOMETRY"}, tmp.file("live.ini"));
    const auto live = test::run(
        "cd " + tmp.path().string() + " && timeout 120 " + test::binDir() + "/wifi-localize -p " +
        test::libDir() + "/libmrpt_wifi_sensor.so " + ini + " -q -o live --stop-when-idle 2");
    ASSERT_EQ(live.exitCode, 0) << live.output;

    const auto a = Trajectory2D::fromTumFile(tmp.file("off/estimate_tum.txt"));
    auto b = Trajectory2D::fromTumFile(tmp.file("live/estimate_tum.txt"));
    ASSERT_GT(a.size(), 100u) << off.output;
    ASSERT_GT(b.size(), 20u) << live.output;
    // The replay runs on the wall clock: its first frame is the capture's first.
    std::smatch m;
    ASSERT_TRUE(std::regex_search(live.output, m, std::regex("first obs\\. at  : ([0-9.]+)")))
        << live.output;
    std::istringstream csv(test::readFile(tmp.file("b.csv")));
    std::string line;
    std::getline(csv, line);  // header
    std::getline(csv, line);
    const double shift = std::stod(m[1]) - std::stod(line.substr(0, line.find(',')));
    for (auto& t : b.t) t -= shift;
    const auto gt = Trajectory2D::fromTumFile(tmp.file("truth/trajectory_tum.txt"));
    const auto d = errorsOf(b, a, 4.0);  // live vs offline, after 4 s
    const auto eLive = errorsOf(b, gt, 4.0), eOff = errorsOf(a, gt, 4.0);
    ASSERT_GT(d.afterWarmup.size(), 10u);
    // Same place within the filter's randomness (the two differ in step batching and random
    // draws), and both where the robot is.
    EXPECT_LE(median(d.afterWarmup), 0.5) << live.output << off.output;
    EXPECT_LE(median(eLive.afterWarmup), 0.5) << "offline: " << median(eOff.afterWarmup);
    EXPECT_LE(median(eOff.afterWarmup), 0.5) << "live: " << median(eLive.afterWarmup);
    std::cout << "live vs offline: median distance " << median(d.afterWarmup)
              << " m; median error live " << median(eLive.afterWarmup) << " m, offline "
              << median(eOff.afterWarmup) << " m\n";
}

TEST(WifiLocalize, MapsDevicesLiveAndEndsWithTheOfflineMap)
{
    // iot.yaml with the odometry in the map frame (start_at_origin: false), so the device map
    // is in the frame of the true positions; the trajectory of both runs is this odometry.
    test::TempDir tmp;
    const auto scenario = tmp.file("iot.yaml");
    {
        std::istringstream in(test::readFile(kShare + "/scenarios/iot.yaml"));
        std::ofstream o(scenario);
        for (std::string line; std::getline(in, line);)
        {
            if (const auto p = line.find("../arrays/"); p != std::string::npos)
                line.replace(p, 2, kShare);
            o << line << "\n";
            if (line.rfind("odometry:", 0) == 0) o << "  start_at_origin: false\n";
        }
    }
    const auto truth = test::run(
        test::binDir() + "/wifi-sim " + scenario + " /dev/null -q -d 1 -t " + tmp.file("truth"));
    ASSERT_EQ(truth.exitCode, 0) << truth.output;
    const auto devicesTruth = tmp.file("truth/transmitters.yaml");

    const double seconds = 16;
    const uint16_t csiPort = test::freeLoopbackPort(SOCK_DGRAM);
    uint16_t odoPort = test::freeLoopbackPort(SOCK_DGRAM);
    if (odoPort == csiPort) odoPort = uint16_t(csiPort + 1);
    test::EmulatorProcess emu(
        {"--scenario", scenario, "--preconfigured", "6/20", "--odometry-port",
         std::to_string(odoPort)},
        csiPort, seconds + 30);
    ASSERT_TRUE(emu.ready()) << emu.log();
    auto keys = baseKeys(csiPort, odoPort);
    keys.erase("wifi-localize/bearing_calibration");  // AoA: no AP calibration needed
    keys["wifi-localize/bearing_algorithm"] =
        "aoa_only\nmap_devices = true\nmap_update_period_s = 2";
    keys["LocalizationExperiment/particles_count"] = "300";
    keys["KLD_options/KLD_minSampleSize"] = keys["KLD_options/KLD_maxSampleSize"] = "300";
    const auto ini = deriveIni(keys, {}, tmp.file("live.ini"));
    const auto live = test::run(
        "cd " + tmp.path().string() + " && timeout " + std::to_string(int(seconds + 60)) + " " +
        test::binDir() + "/wifi-localize -p " + test::libDir() + "/libmrpt_wifi_sensor.so " + ini +
        " -o live -r seen.rawlog --devices-truth " + devicesTruth + " -d " +
        std::to_string(int(seconds)));
    emu.stop();
    ASSERT_EQ(live.exitCode, 0) << live.output;

    // While driving: the device map is printed every 2 s, and devices appear on it.
    const std::regex liveLine(R"(\] t=[0-9.]+s devices:([^\n]*))");
    std::vector<std::string> updates;
    for (std::sregex_iterator it(live.output.begin(), live.output.end(), liveLine), end; it != end;
         ++it)
        updates.push_back((*it)[1]);
    ASSERT_GE(updates.size(), 4u) << live.output;
    EXPECT_NE(updates.back().find("thermostat ("), std::string::npos) << live.output;
    EXPECT_NE(updates.back().find("camera ("), std::string::npos) << live.output;

    // Offline, on what wifi-localize recorded (its bearings and the odometry stream).
    const auto off = test::run(
        test::binDir() + "/wifi-iot-map -r " + tmp.file("seen.rawlog") +
        " --trust-odometry --truth " + devicesTruth + " -q --no-plots -o " + tmp.file("off"));
    ASSERT_EQ(off.exitCode, 0) << off.output;
    const auto liveCsv = test::readFile(tmp.file("live/devices.csv"));
    const auto offCsv = test::readFile(tmp.file("off/devices.csv"));
    // The final live map is the offline map: same devices, positions, covariances, counts.
    EXPECT_EQ(liveCsv, offCsv) << live.output << off.output;
    size_t localized = 0;
    std::istringstream csv(liveCsv);
    std::string line;
    std::getline(csv, line);  // header
    while (std::getline(csv, line)) localized += line.find(",1,") != std::string::npos;
    EXPECT_EQ(localized, 3u) << liveCsv;
    std::cout << live.output.substr(live.output.find("  device map")) << "\n";
}

// ---- no usable CSI: the cause, what to check, and its exit status (docs/troubleshooting.md)

namespace
{
struct NoCsiRun
{
    test::CommandResult result;
    double seconds = 0;   // wall time of the run
    std::string summary;  // out/summary.txt
};

/** wifi-localize on the emulator's .ini (no odometry section) with `keys` changed, the CSI
 *  sensor on UDP `csiPort`, no_csi_timeout_s = `timeout_s`; bounded by `timeout`. No AP
 *  calibration: these runs never get as far as weighing a bearing. */
NoCsiRun runWithoutUsableCsi(
    const test::TempDir& tmp, uint16_t csiPort, double timeout_s,
    std::map<std::string, std::string> keys, const std::string& args = "")
{
    keys.insert(
        {{"WIFI_CSI/udp_port", std::to_string(csiPort)},
         {"wifi-localize/bearing_array", kShare + "/arrays/rt-ac86u.yaml"},
         {"wifi-localize/bearing_tx_arrays", kShare + "/arrays/ap-linear-4.yaml"},
         {"wifi-localize/no_csi_timeout_s", std::to_string(timeout_s)},
         {"MetricMap_wifiBearingMap_00_creationOpts/transmitters_file",
          kShare + "/localization/kidnapped-aps.yaml"},
         {"LocalizationExperiment/particles_count", "300"},
         {"KLD_options/KLD_minSampleSize", "300"},
         {"KLD_options/KLD_maxSampleSize", "300"}});
    const auto ini = deriveIni(keys, {"ODOMETRY"}, tmp.file("nocsi.ini"));
    NoCsiRun r;
    const auto t0 = std::chrono::steady_clock::now();
    r.result = test::run(
        "cd " + tmp.path().string() + " && timeout 180 " + test::binDir() + "/wifi-localize -p " +
        test::libDir() + "/libmrpt_wifi_sensor.so " + ini + " -q -o out " + args);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.summary = test::readFile(tmp.file("out/summary.txt"));
    return r;
}
}  // namespace

TEST(WifiLocalizeNoCsi, UnreachableRouterIsNamedWithItsExitStatusWithinTheTimeout)
{
    test::TempDir tmp;
    // The router's ssh port: nobody listens there; the key file named does not exist either
    // (ssh then warns about it first, and the cause must still be the refused connection).
    const auto r = runWithoutUsableCsi(
        tmp, test::freeLoopbackPort(SOCK_DGRAM), 3,
        {{"WIFI_CSI/router_control",
          "true\nlogin_host = 127.0.0.1\nlogin_port = " + std::to_string(test::freeLoopbackPort()) +
              "\nlogin_identity_file = " + tmp.file("no_such_key") +
              "\nlogin_known_hosts = " + tmp.file("known_hosts") + "\nlogin_connect_timeout = 2"}});
    EXPECT_EQ(r.result.exitCode, 4) << r.result.output;
    EXPECT_NE(r.result.output.find("no usable CSI for 3 s"), std::string::npos) << r.result.output;
    EXPECT_NE(r.result.output.find("router control failed"), std::string::npos) << r.result.output;
    EXPECT_NE(r.result.output.find("connection refused"), std::string::npos) << r.result.output;
    EXPECT_NE(r.result.output.find("no_such_key"), std::string::npos) << r.result.output;
    EXPECT_NE(r.summary.find("WARNING        : 0 CSI frames"), std::string::npos) << r.summary;
    EXPECT_NE(r.summary.find("exit status    : 4"), std::string::npos) << r.summary;
    // It waited for the timeout, and not much longer (generous bound for a loaded machine).
    EXPECT_GE(r.seconds, 3.0);
    EXPECT_LT(r.seconds, 60.0);
}

TEST(WifiLocalizeNoCsi, EmulatorNotStreamingIsNoDatagrams)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    // Not --preconfigured: the emulated router extracts no CSI until configured.
    test::EmulatorProcess emu({"--scenario", kShare + "/scenarios/kidnapped.yaml"}, port, 120);
    ASSERT_TRUE(emu.ready()) << emu.log();
    const auto r = runWithoutUsableCsi(tmp, port, 3, {});
    EXPECT_EQ(r.result.exitCode, 5) << r.result.output;
    EXPECT_NE(
        r.result.output.find("no datagram at all on UDP 127.0.0.1:" + std::to_string(port)),
        std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find("csi-router configure"), std::string::npos) << r.result.output;
    EXPECT_NE(r.summary.find("WARNING        : 0 CSI frames"), std::string::npos) << r.summary;
}

TEST(WifiLocalizeNoCsi, KeepWaitingKeepsRunningAndWarnsEachTimeout)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu({"--scenario", kShare + "/scenarios/kidnapped.yaml"}, port, 120);
    ASSERT_TRUE(emu.ready()) << emu.log();
    const auto r = runWithoutUsableCsi(tmp, port, 2, {}, "--keep-waiting -d 7");
    // Ran to its duration, warning with the cause on the way; the run as a whole had no CSI,
    // so it still ends with that cause's status.
    EXPECT_NE(r.summary.find("stopped        : duration reached"), std::string::npos)
        << r.summary << r.result.output;
    EXPECT_GE(r.seconds, 7.0);
    size_t warnings = 0;
    for (size_t at = 0;
         (at = r.result.output.find("--keep-waiting: still waiting", at)) != std::string::npos;
         ++at)
        ++warnings;
    EXPECT_GE(warnings, 2u) << r.result.output;
    EXPECT_NE(r.result.output.find("no datagram at all"), std::string::npos) << r.result.output;
    EXPECT_EQ(r.result.exitCode, 5) << r.result.output;
}

TEST(WifiLocalizeNoCsi, DatagramsFromAnotherAddressNameTheAddressSeen)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu(
        {"--scenario", kShare + "/scenarios/kidnapped.yaml", "--preconfigured", "155/80"}, port,
        120);
    ASSERT_TRUE(emu.ready()) << emu.log();
    // The real router's CSI source address; the emulator sends from 127.0.0.1.
    const auto r = runWithoutUsableCsi(tmp, port, 3, {{"WIFI_CSI/router_address", "10.10.10.10"}});
    EXPECT_EQ(r.result.exitCode, 6) << r.result.output;
    EXPECT_NE(
        r.result.output.find("router_address = 10.10.10.10 (seen: 127.0.0.1)"), std::string::npos)
        << r.result.output;
}

TEST(WifiLocalizeNoCsi, FramesWithoutABearingChainSaySo)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu(
        {"--scenario", kShare + "/scenarios/kidnapped.yaml", "--preconfigured", "155/80"}, port,
        120);
    ASSERT_TRUE(emu.ready()) << emu.log();
    const auto r = runWithoutUsableCsi(tmp, port, 3, {{"wifi-localize/bearing_algorithm", ""}});
    EXPECT_EQ(r.result.exitCode, 7) << r.result.output;
    EXPECT_NE(r.result.output.find("nothing turns them into bearings"), std::string::npos)
        << r.result.output;
}

TEST(WifiLocalizeNoCsi, ASensorThatFailsEndsTheRunWithStatus1NotAnAbort)
{
    test::TempDir tmp;
    // abort_on_error: the router control failure ends the sensor's thread with an exception.
    const auto r = runWithoutUsableCsi(
        tmp, test::freeLoopbackPort(SOCK_DGRAM), 30,
        {{"WIFI_CSI/router_control",
          "true\nabort_on_error = true\nlogin_host = 127.0.0.1\n"
          "login_port = " +
              std::to_string(test::freeLoopbackPort())}});
    EXPECT_EQ(r.result.exitCode, 1) << r.result.output;
    EXPECT_NE(r.result.output.find("a sensor failed"), std::string::npos) << r.result.output;
    EXPECT_NE(r.result.output.find("connection refused"), std::string::npos) << r.result.output;
}

TEST(WifiLocalizeNoCsi, BearingsFromTransmittersOutsideTheMapNameThem)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    test::EmulatorProcess emu(
        {"--scenario", kShare + "/scenarios/kidnapped.yaml", "--preconfigured", "155/80"}, port,
        120);
    ASSERT_TRUE(emu.ready()) << emu.log();
    // AoA needs no AP calibration; the map is another building's (other MAC addresses), as
    // when the router listens on a channel where the map's access points do not transmit.
    const auto r = runWithoutUsableCsi(
        tmp, port, 4,
        {{"wifi-localize/bearing_algorithm", "aoa_only"},
         {"MetricMap_wifiBearingMap_00_creationOpts/transmitters_file",
          kShare + "/localization/loop-aps.yaml"}});
    EXPECT_EQ(r.result.exitCode, 8) << r.result.output;
    EXPECT_NE(
        r.result.output.find("none from a transmitter of the AP map (heard 02:00:00:00:01:0"),
        std::string::npos)
        << r.result.output;
    EXPECT_NE(r.result.output.find("155/80"), std::string::npos) << r.result.output;
}
