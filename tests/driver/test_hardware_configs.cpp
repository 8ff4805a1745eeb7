// The configs shipped for real hardware (share/rawlog-grabber/rt-ac86u_robot.ini,
// share/localization/wifi-localize-rt-ac86u.ini, aps.example.yaml) and the UDP odometry sender
// (share/odometry/send_odometry.py), run through the real programs: Debian's rawlog-grabber and
// wifi-localize against the RT-AC86U emulator, configured over a real sshd on 127.0.0.1. Only
// the values the files mark `FILL IN:` or `CHECK:` are changed (to loopback ones); the test
// checks that every key it changes is marked. Also: a copied .ini keeps its relative paths.
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/sensor/CWiFiOdometryUdpSensor.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "EmulatorProcess.h"
#include "GrabberRun.h"
#include "SshdFixture.h"

using namespace mrpt_wifi;
namespace fs = std::filesystem;

namespace
{
const std::string kShare = test::sourceDir() + "/share";

/** `SECTION/key` -> value. */
using Keys = std::map<std::string, std::string>;

/** The keys of a shipped .ini whose comment block just above says `FILL IN:` or `CHECK:`,
 *  as `SECTION/key`. */
std::set<std::string> markedKeys(const std::string& iniPath)
{
    std::set<std::string> marked;
    std::istringstream in(test::readFile(iniPath));
    std::string section, comments;
    for (std::string line; std::getline(in, line);)
    {
        if (line.empty())
            comments.clear();
        else if (line[0] == ';' || line[0] == '#')
            comments += line + "\n";
        else if (line[0] == '[')
            section = line.substr(1, line.find(']') - 1), comments.clear();
        else if (const auto eq = line.find('='); eq != std::string::npos)
        {
            std::string key = line.substr(0, eq);
            key.erase(key.find_last_not_of(" \t") + 1);
            if (comments.find("FILL IN") != std::string::npos ||
                comments.find("CHECK:") != std::string::npos)
                marked.insert(section + "/" + key);
            comments.clear();
        }
    }
    return marked;
}

/** A copy of a shipped .ini at `out` with `keys` (SECTION/key) set; every one must exist in
 *  the file already (a test changes values, it adds none). */
void deriveIni(const std::string& shipped, const Keys& keys, const std::string& out)
{
    std::istringstream in(test::readFile(shipped));
    std::ostringstream o;
    std::set<std::string> done;
    std::string section;
    for (std::string line; std::getline(in, line);)
    {
        if (!line.empty() && line[0] == '[') section = line.substr(1, line.find(']') - 1);
        const auto eq = line.find('=');
        if (eq != std::string::npos && line[0] != ';' && line[0] != '#')
        {
            std::string key = line.substr(0, eq);
            key.erase(key.find_last_not_of(" \t") + 1);
            if (auto it = keys.find(section + "/" + key); it != keys.end())
            {
                o << key << " = " << it->second << "\n";
                done.insert(it->first);
                continue;
            }
        }
        o << line << "\n";
    }
    for (const auto& [k, v] : keys) EXPECT_TRUE(done.count(k)) << k << " is not in " << shipped;
    std::ofstream(out) << o.str();
}

/** The substitutions of the router's and the robot's addresses: loopback, the test sshd. */
Keys loopbackKeys(const test::SshdFixture& sshd, uint16_t csiPort, uint16_t odoPort)
{
    return {
        {"WIFI_CSI/login_host", "127.0.0.1"},
        {"WIFI_CSI/login_port", std::to_string(sshd.port())},
        {"WIFI_CSI/login_user", sshd.user()},
        {"WIFI_CSI/login_identity_file", sshd.clientKey()},
        {"WIFI_CSI/login_known_hosts", sshd.knownHosts()},
        {"WIFI_CSI/router_address", "127.0.0.1"},
        {"WIFI_CSI/udp_bind_address", "127.0.0.1"},
        {"WIFI_CSI/udp_port", std::to_string(csiPort)},
        {"ODOMETRY/udp_port", std::to_string(odoPort)},
        // The emulator plays share/scenarios/kidnapped.yaml: 4 APs on 155/80. Three of them
        // in the filters: the fourth must not be recorded.
        {"WIFI_CSI/channel", "155/80"},
        {"WIFI_CSI/mac_filter", "02:00:00:00:01:01,02:00:00:00:01:02,02:00:00:00:01:03"},
        {"WIFI_CSI/packet_mac_filter", "02:00:00:00:01:01,02:00:00:00:01:02,02:00:00:00:01:03"}};
}

void expectOnlyMarkedKeysChanged(const std::string& shipped, const Keys& keys)
{
    const auto marked = markedKeys(shipped);
    for (const auto& [k, v] : keys)
        EXPECT_TRUE(marked.count(k)) << shipped << ": the test changes " << k
                                     << ", which the file does not mark FILL IN / CHECK";
}

std::pair<uint16_t, uint16_t> twoFreeUdpPorts()
{
    const uint16_t a = test::freeLoopbackPort(SOCK_DGRAM);
    uint16_t b = test::freeLoopbackPort(SOCK_DGRAM);
    for (int i = 0; i < 10 && b == a; ++i) b = test::freeLoopbackPort(SOCK_DGRAM);
    return {a, b};
}

std::unique_ptr<CWiFiOdometryUdpSensor> odometrySensor(uint16_t port)
{
    mrpt::config::CConfigFileMemory ini;
    ini.setContent(
        "[ODOMETRY]\ndriver = CWiFiOdometryUdpSensor\nprocess_rate = 100\nsensorLabel = "
        "ODOMETRY\nudp_bind_address = 127.0.0.1\nudp_port = " +
        std::to_string(port) + "\n");
    auto sensor = std::make_unique<CWiFiOdometryUdpSensor>();
    sensor->loadConfig(ini, "ODOMETRY");
    sensor->initialize();
    return sensor;
}

/** Every odometry observation the sensor has queued. */
std::vector<mrpt::obs::CObservationOdometry::Ptr> drain(CWiFiOdometryUdpSensor& sensor)
{
    sensor.doProcess();
    mrpt::hwdrivers::CGenericSensor::TListObservations obs;
    sensor.getObservations(obs);
    std::vector<mrpt::obs::CObservationOdometry::Ptr> out;
    for (const auto& [t, o] : obs)
        if (auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
            out.push_back(odo);
    return out;
}

std::string sender()
{
    return "python3 " + kShare + "/odometry/send_odometry.py";
}
}  // namespace

TEST(HardwareConfigs, OdometrySenderReachesTheSensor)
{
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    auto sensor = odometrySensor(port);
    // The example circle, as fast as it can send (the datagrams wait in the socket's buffer);
    // --print echoes every line sent: the sensor must have received exactly those poses.
    const auto sent =
        test::run(sender() + " --port " + std::to_string(port) + " --count 40 --rate 0 --print");
    ASSERT_EQ(sent.exitCode, 0) << sent.output;
    const auto got = drain(*sensor);
    std::istringstream lines(sent.output);
    size_t i = 0;
    for (std::string line; std::getline(lines, line);)
    {
        if (line.rfind("MRPT_WIFI_ODO", 0) != 0) continue;
        ASSERT_LT(i, got.size()) << "pose " << i << " sent, not received\n" << sent.output;
        std::istringstream f(line.substr(14));
        unsigned version = 0, seq = 0;
        double t, x, y, phi, vx, vy, w;
        ASSERT_TRUE(f >> version >> seq >> t >> x >> y >> phi >> vx >> vy >> w) << line;
        EXPECT_EQ(seq, i);
        EXPECT_DOUBLE_EQ(got[i]->odometry.x(), x);
        EXPECT_DOUBLE_EQ(got[i]->odometry.y(), y);
        EXPECT_NEAR(got[i]->odometry.phi(), phi, 1e-12);
        EXPECT_TRUE(got[i]->hasVelocities);
        EXPECT_DOUBLE_EQ(got[i]->velocityLocal.vx, vx);
        EXPECT_DOUBLE_EQ(got[i]->velocityLocal.omega, w);
        EXPECT_EQ(got[i]->sensorLabel, "ODOMETRY");
        ++i;
    }
    EXPECT_EQ(i, 40u);
    EXPECT_EQ(got.size(), 40u);
    EXPECT_EQ(sensor->lost(), 0u);
    EXPECT_EQ(sensor->malformed(), 0u);
    // It drove: the circle's last pose is away from the first.
    EXPECT_GT(std::hypot(got.back()->odometry.x(), got.back()->odometry.y()), 0.1);

    // The pipe: "X Y PHI [VX VY OMEGA]" lines from another program, comments skipped.
    const auto piped = test::run(
        "printf '# x y phi\\n1.5 -2 0.25\\n1.6 -2 0.3 0.4 0 0.1\\n' | " + sender() +
        " --stdin --port " + std::to_string(port));
    ASSERT_EQ(piped.exitCode, 0) << piped.output;
    const auto two = drain(*sensor);
    ASSERT_EQ(two.size(), 2u) << piped.output;
    EXPECT_DOUBLE_EQ(two[0]->odometry.x(), 1.5);
    EXPECT_DOUBLE_EQ(two[0]->odometry.y(), -2);
    EXPECT_DOUBLE_EQ(two[0]->odometry.phi(), 0.25);
    EXPECT_DOUBLE_EQ(two[1]->velocityLocal.vx, 0.4);
    // A restart of the sequence from 0 is not a loss.
    EXPECT_EQ(sensor->lost(), 0u);

    // Bad input: the line named, exit 1, nothing sent for it.
    const auto bad =
        test::run("printf '1 2\\n' | " + sender() + " --stdin --port " + std::to_string(port));
    EXPECT_EQ(bad.exitCode, 1) << bad.output;
    EXPECT_NE(bad.output.find("stdin line 1"), std::string::npos) << bad.output;
    EXPECT_TRUE(drain(*sensor).empty());
    // --count bounds the pipe too.
    const auto bounded = test::run(
        "yes '0 0 0' | head -n 1000 | " + sender() + " --stdin --count 5 --port " +
        std::to_string(port));
    EXPECT_EQ(bounded.exitCode, 0) << bounded.output;
    EXPECT_EQ(drain(*sensor).size(), 5u);
}

TEST(HardwareConfigs, RobotIniRecordsCsiAndOdometryFromTheEmulator)
{
    test::TempDir tmp;
    const auto [csiPort, odoPort] = twoFreeUdpPorts();
    // A freshly booted router (no --preconfigured): the sensor sets it up over ssh. The
    // emulator streams the scenario's wheel odometry as the robot's software would.
    test::EmulatorProcess emu(
        {"--scenario", kShare + "/scenarios/kidnapped.yaml", "--odometry-port",
         std::to_string(odoPort), "--max-datagrams", "40000"},
        csiPort, 60);
    ASSERT_TRUE(emu.ready()) << emu.log();
    test::SshdFixture sshd(emu.toolsDir());
    MRPT_WIFI_REQUIRE_SSHD(sshd);

    const std::string shipped = kShare + "/rawlog-grabber/rt-ac86u_robot.ini";
    const auto keys = loopbackKeys(sshd, csiPort, odoPort);
    expectOnlyMarkedKeysChanged(shipped, keys);
    deriveIni(shipped, keys, tmp.file("robot.ini"));
    const auto rec = test::runGrabber(tmp, tmp.file("robot.ini"), 6.0);
    emu.stop();
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    EXPECT_NE(rec.log.find("router configured: CSI on 155/80"), std::string::npos) << rec.log;

    ASSERT_FALSE(rec.frames.empty()) << rec.log;
    std::set<std::string> transmitters;
    for (const auto& f : rec.frames)
    {
        EXPECT_EQ(f->chanspec.centerChannel, 155);
        EXPECT_EQ(f->sensorLabel, "WIFI_CSI");
        transmitters.insert(f->transmitter.asString());
    }
    // The fourth AP (02:00:00:00:01:04) passes the firmware's two-byte filter, not mac_filter.
    EXPECT_EQ(
        transmitters,
        (std::set<std::string>{"02:00:00:00:01:01", "02:00:00:00:01:02", "02:00:00:00:01:03"}));
    // The odometry in the same rawlog, from the UDP sensor: the robot moved.
    std::vector<mrpt::obs::CObservationOdometry::Ptr> odo;
    for (const auto& entry : fs::directory_iterator(tmp.path()))
        if (entry.path().extension() == ".rawlog")
            for (const auto& o : test::readRawlog(entry.path().string()))
                if (auto p = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
                    odo.push_back(p);
    ASSERT_GE(odo.size(), 2u) << rec.log;
    EXPECT_EQ(odo.front()->sensorLabel, "ODOMETRY");
    double travelled = 0;
    for (size_t i = 1; i < odo.size(); ++i)
        travelled += (odo[i]->odometry - odo[i - 1]->odometry).norm();
    EXPECT_GT(travelled, 0.0);
    std::cout << rec.frames.size() << " CSI frames, " << odo.size() << " odometry poses ("
              << travelled << " m)\n";
}

TEST(HardwareConfigs, WifiLocalizeIniLocalizesOnTheEmulator)
{
    test::TempDir tmp;
    const auto [csiPort, odoPort] = twoFreeUdpPorts();
    const double seconds = 10;
    test::EmulatorProcess emu(
        {"--scenario", kShare + "/scenarios/kidnapped.yaml", "--odometry-port",
         std::to_string(odoPort)},
        csiPort, seconds + 40);
    ASSERT_TRUE(emu.ready()) << emu.log();
    test::SshdFixture sshd(emu.toolsDir());
    MRPT_WIFI_REQUIRE_SSHD(sshd);

    const std::string shipped = kShare + "/localization/wifi-localize-rt-ac86u.ini";
    auto keys = loopbackKeys(sshd, csiPort, odoPort);
    // The emulated receiver has no chain phase offsets: it needs no receive calibration.
    keys["wifi-localize/bearing_calibration"] = "";
    // The AP map: the example, copied beside the .ini as a user would (its values are the
    // emulator's scenario), under the name the user gives it.
    fs::copy_file(kShare + "/localization/aps.example.yaml", tmp.file("aps.yaml"));
    keys["MetricMap_wifiBearingMap_00_creationOpts/transmitters_file"] = "aps.yaml";
    // fewer particles than the shipped file: the test shares the machine
    keys["LocalizationExperiment/particles_count"] = "1000";
    keys["KLD_options/KLD_minSampleSize"] = keys["KLD_options/KLD_maxSampleSize"] = "1000";
    auto marked = keys;
    for (const char* k :
         {"LocalizationExperiment/particles_count", "KLD_options/KLD_minSampleSize",
          "KLD_options/KLD_maxSampleSize"})
        marked.erase(k);
    expectOnlyMarkedKeysChanged(shipped, marked);
    deriveIni(shipped, keys, tmp.file("localize.ini"));

    // Run from another folder: the AP map is found beside the .ini, the array by name.
    test::TempDir cwd;
    const auto live = test::run(
        "cd " + cwd.path().string() + " && timeout " + std::to_string(int(seconds + 60)) + " " +
        test::binDir() + "/wifi-localize -p " + test::libDir() + "/libmrpt_wifi_sensor.so " +
        tmp.file("localize.ini") + " -o " + tmp.file("out") + " -d " +
        std::to_string(int(seconds)));
    emu.stop();
    ASSERT_EQ(live.exitCode, 0) << live.output;
    EXPECT_NE(live.output.find("router configured: CSI on 155/80"), std::string::npos)
        << live.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        live.output, m,
        std::regex(R"(observations\s*:\s*([0-9]+) CSI, ([0-9]+) odometry, ([0-9]+) bearings)")))
        << live.output;
    EXPECT_GT(std::stoul(m[1]), 0u) << live.output;
    EXPECT_GT(std::stoul(m[2]), 0u) << live.output;
    EXPECT_GT(std::stoul(m[3]), 0u) << live.output;
    // Estimates written, inside the building's area of the .ini (0..10 x 0..5 m).
    std::istringstream tum(test::readFile(tmp.file("out/estimate_tum.txt")));
    size_t estimates = 0;
    for (std::string line; std::getline(tum, line);)
    {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream f(line);
        double t, x, y;
        ASSERT_TRUE(f >> t >> x >> y) << line;
        EXPECT_GE(x, -0.5);
        EXPECT_LE(x, 10.5);
        EXPECT_GE(y, -0.5);
        EXPECT_LE(y, 5.5);
        ++estimates;
    }
    EXPECT_GT(estimates, 0u) << live.output;
    std::cout << m[0] << "; " << estimates << " estimates\n";
}

TEST(HardwareConfigs, CopiedIniKeepsItsRelativePathsUnderRawlogGrabber)
{
    // rawlog-grabber hands the sensor a copy of the .ini's text, not its path: the sensor
    // finds the file on rawlog-grabber's command line. The .ini lives in one folder with its
    // capture beside it, rawlog-grabber runs in another, and the array is given by name.
    test::TempDir cfg, cwd;
    fs::copy_file(kShare + "/samples/sample_4x4_80mhz.pcap", cfg.file("capture.pcap"));
    std::ofstream(cfg.file("replay.ini"))
        << "[global]\nrawlog_prefix = replay\ntime_between_launches = 100\nuse_sensoryframes = "
           "false\nGRABBER_PERIOD_MS = 200\n\n[CSI]\ndriver = CWiFiCSISensor\nprocess_rate = "
           "200\nsensorLabel = CSI\nmax_queue_len = 100000\nsource = pcap\npcap_file = "
           "capture.pcap\nrouter_control = false\nbearing_algorithm = aoa_only\nbearing_array = "
           "rt-ac86u\n";
    const auto rec = test::runGrabber(cwd, cfg.file("replay.ini"), 4.0);
    ASSERT_EQ(rec.exitCode, 0) << rec.log;
    EXPECT_FALSE(rec.frames.empty()) << rec.log;
    size_t bearings = 0;
    for (const auto& entry : fs::directory_iterator(cwd.path()))
        if (entry.path().extension() == ".rawlog")
            for (const auto& o : test::readRawlog(entry.path().string()))
                bearings += std::dynamic_pointer_cast<CObservationWiFiBearing>(o) != nullptr;
    EXPECT_GT(bearings, 0u) << rec.log;
    // No note: both were found where the .ini says (beside it; the array by name).
    EXPECT_EQ(rec.log.find("working directory"), std::string::npos) << rec.log;

    // Without the file beside the .ini: an error naming the key and where it looked.
    fs::remove(cfg.file("capture.pcap"));
    const auto missing = test::runGrabber(cwd, cfg.file("replay.ini"), 1.0);
    EXPECT_NE(missing.log.find("'pcap_file' = capture.pcap"), std::string::npos) << missing.log;
    EXPECT_NE(missing.log.find(cfg.file("capture.pcap")), std::string::npos) << missing.log;
}

TEST(HardwareConfigs, InstalledPluginFindsTheInstalledDataFolder)
{
    // `cmake --install` under any prefix puts share/ at <prefix>/share/mrpt_wifi; the installed
    // plugin finds its files there (not in this source tree): an array present only in the
    // installed folder is found by name, and a shipped .ini's own form (../samples/...) of a
    // copy elsewhere resolves there too.
    test::TempDir prefix, cfg, cwd;
    const auto inst =
        test::run("cmake --install " + test::binDir() + "/.. --prefix " + prefix.path().string());
    ASSERT_EQ(inst.exitCode, 0) << inst.output;
    const fs::path data = prefix.path() / "share/mrpt_wifi";
    ASSERT_TRUE(fs::exists(data / "rawlog-grabber/rt-ac86u_robot.ini"));
    ASSERT_TRUE(fs::exists(data / "odometry/send_odometry.py"));
    fs::copy_file(data / "arrays/rt-ac86u.yaml", data / "arrays/only-installed.yaml");
    std::ofstream(cfg.file("replay.ini"))
        << "[global]\nrawlog_prefix = replay\ntime_between_launches = 100\nuse_sensoryframes = "
           "false\nGRABBER_PERIOD_MS = 200\n\n[CSI]\ndriver = CWiFiCSISensor\nprocess_rate = "
           "200\nsensorLabel = CSI\nmax_queue_len = 100000\nsource = pcap\npcap_file = "
           "../samples/sample_4x4_80mhz.pcap\nrouter_control = false\nbearing_algorithm = "
           "aoa_only\nbearing_array = only-installed\n";
    fs::path lib = prefix.path() / "lib/libmrpt_wifi_sensor.so";
    for (const auto& e : fs::recursive_directory_iterator(prefix.path()))
        if (e.path().filename() == "libmrpt_wifi_sensor.so") lib = e.path();
    const auto rec = test::run(
        "cd " + cwd.path().string() + " && (sleep 3; echo) | timeout 60 rawlog-grabber -p " +
        lib.string() + " " + cfg.file("replay.ini"));
    ASSERT_EQ(rec.exitCode, 0) << rec.output;
    EXPECT_NE(
        rec.output.find("replaying " + (data / "samples/sample_4x4_80mhz.pcap").string()),
        std::string::npos)
        << rec.output;
    EXPECT_NE(rec.output.find("live bearings: aoa_only"), std::string::npos) << rec.output;
}
