// The real programs: rt-ac86u-emulator started as a process, driven through the links in
// STATE_DIR/bin/ (the shim finds the socket from the link's own directory), stopped by
// emulator-ctl or SIGTERM. Everything on 127.0.0.1, each run bounded by --duration.
#include <gtest/gtest.h>
#include <mrpt_wifi/emulator/CsiParams.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "EmulatorTestSupport.h"

using namespace mrpt_wifi;
using test::run;

extern char** environ;

namespace
{
const char* kScenarioYaml = R"(name: cli-test
duration_s: 60
seed: 3
transmitters:
  - {name: ap-a, mac: '02:aa:00:00:00:01', position: [4, 1], channel: 155/80, frame_rate_hz: 100}
  - {name: ap-c, mac: '02:bb:00:00:00:04', position: [2, 3], channel: 42/80, frame_rate_hz: 100}
receiver:
  array: {name: rt-ac86u, elements: [[0, 0], [0, 0.052], [0, 0.026], [0, 0.078]]}
motion: {type: static, start: [0, 0, 0]}
odometry: {enabled: false}
)";

std::string emulatorProgram()
{
    return test::binDir() + "/rt-ac86u-emulator";
}

/** rt-ac86u-emulator as a child process, stdout/stderr to files. */
class EmulatorProcess
{
public:
    EmulatorProcess(const test::TempDir& tmp, const std::string& args) : tmp_(tmp)
    {
        const std::string cmd = "exec " + emulatorProgram() + " " + args + " > " +
                                tmp.file("stdout.txt") + " 2> " + tmp.file("stderr.txt");
        const char* argv[] = {"sh", "-c", cmd.c_str(), nullptr};
        if (posix_spawnp(&pid_, "sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0)
            pid_ = -1;
    }
    ~EmulatorProcess()
    {
        if (pid_ > 0 && !exited_)
        {
            ::kill(pid_, SIGKILL);
            wait(5);
        }
    }
    bool waitForSocket(const std::string& path, double max_s = 10)
    {
        const auto t0 = test::Clock::now();
        while (test::secondsSince(t0) < max_s)
        {
            if (std::filesystem::exists(path)) return true;
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        return false;
    }
    /** Exit code, or -1 if it doesn't end within max_s. */
    int wait(double max_s)
    {
        const auto t0 = test::Clock::now();
        while (test::secondsSince(t0) < max_s)
        {
            int status = 0;
            if (::waitpid(pid_, &status, WNOHANG) == pid_)
            {
                exited_ = true;
                return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        return -1;
    }
    pid_t pid() const { return pid_; }
    std::string out() const { return test::readFile(tmp_.file("stdout.txt")); }
    std::string err() const { return test::readFile(tmp_.file("stderr.txt")); }

private:
    const test::TempDir& tmp_;
    pid_t pid_ = -1;
    bool exited_ = false;
};

std::string writeScenario(const test::TempDir& tmp)
{
    const std::string path = tmp.file("scenario.yaml");
    std::ofstream(path) << kScenarioYaml;
    return path;
}

/** A command as an sshd session would run it: no socket variable, PATH as given. */
std::string shell(const std::string& command)
{
    return "env -u RT_AC86U_EMULATOR_SOCKET " + command;
}
}  // namespace

TEST(EmulatorCli, HelpAndBadInputExitWithClearMessages)
{
    test::TempDir tmp;
    const std::string scenario = writeScenario(tmp);
    auto r = run(emulatorProgram() + " --help");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("--scenario"), std::string::npos);

    for (const char* dest : {"192.168.1.10", "10.10.10.10", "255.255.255.255", "::ffff:127.0.0.1"})
    {
        r =
            run(emulatorProgram() + " --scenario " + scenario + " --state-dir " + tmp.file("s") +
                " --duration 1 --dest " + dest);
        EXPECT_NE(r.exitCode, 0) << dest;
        EXPECT_NE(r.output.find("loopback"), std::string::npos) << r.output;
    }
    r = run(emulatorProgram() + " --scenario " + tmp.file("missing.yaml") + " --duration 1");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("missing.yaml"), std::string::npos) << r.output;
    r = run(emulatorProgram() + " --replay " + tmp.file("missing.pcap") + " --duration 1");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("missing.pcap"), std::string::npos) << r.output;
    r = run(emulatorProgram() + " --scenario " + scenario + " --loss 1.5 --duration 1");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("loss"), std::string::npos) << r.output;
    r = run(emulatorProgram() + " --scenario " + scenario + " --preconfigured 999/80 --duration 1");
    EXPECT_NE(r.exitCode, 0);
    r = run(emulatorProgram() + " --scenario " + scenario + " --format bogus --duration 1");
    EXPECT_NE(r.exitCode, 0);
}

TEST(EmulatorCli, ShimLinksDriveTheRunningEmulator)
{
    test::TempDir tmp;
    test::UdpReceiver rx;
    const std::string state = tmp.file("state"), bin = state + "/bin/";
    EmulatorProcess emu(
        tmp, "--scenario " + writeScenario(tmp) + " --port " + std::to_string(rx.port()) +
                 " --state-dir " + state + " --duration 20 --status-period 0");
    ASSERT_TRUE(emu.waitForSocket(state + "/emulator.sock")) << emu.err();

    // Through the link, socket found from the link's directory.
    auto r = run(shell(bin + "wl -i eth6 chanspec 36/80"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    r = run(shell(bin + "wl -i eth6 chanspec"));
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.output, "36/80 (0xe02a)\n");  // control channel 36: centre 42
    // As a shell running bare names through PATH (an sshd whose PATH starts with bin/).
    r = run(shell("PATH=" + bin + ":/usr/bin:/bin wl -i eth6 chanspec"));
    EXPECT_EQ(r.output, "36/80 (0xe02a)\n");
    r = run(shell(bin + "emulator-ctl status"));
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_NE(
        r.output.find("\"chanspec\": \"42/80\", \"chanspec_word\": \"0xe02a\""), std::string::npos)
        << r.output;

    // Errors keep their exit codes and stderr.
    r = run(shell(bin + "wl -i eth6 frobnicate"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("wl: "), std::string::npos);
    r = run(shell(bin + "nexutil -I eth6 -s500 -b -l34 -v AAAA"));
    EXPECT_NE(r.exitCode, 0);
    r = run(shell(bin + "makecsiparams -e 1 -c 155/80 -C 0xf -N 0xf -m 11:22:33:44:55:66 -d 0x50"));
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.output, "m+AB/wAAAQARIjNEVWYAAAAAAAAAAAAAAAAAAAAAAABQAA==\n");
    r = run(shell(bin + "makecsiparams -C 0x1f"));
    EXPECT_NE(r.exitCode, 0);

    // A full WiROS setup through the links makes CSI flow on loopback.
    const std::string setup = bin + "rmmod dhd; " + bin + "insmod /jffs/csi/dhd.ko && " + bin +
                              "brctl addif br0 eth6 && " + bin + "wl -i eth6 chanspec 155/80 && " +
                              bin + "wl -i eth6 monitor 1 && " + bin +
                              "nexutil -I eth6 -s500 -b -l34 -v $(" + bin +
                              "makecsiparams -e 1 -c 155/80 -C 0xf -N 0xf)";
    r = run(shell("sh -c '" + setup + "'"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    // CSI flows, and nothing arrives that the emulator did not send (no fixed count: how much
    // it sends in 400 ms depends on how busy the machine is).
    const size_t received = rx.count();
    const auto sentSoFar =
        test::jsonCounter(run(shell(bin + "emulator-ctl status")).output, "datagrams_sent");
    EXPECT_GT(received, 0u);
    EXPECT_LE(received, sentSoFar);

    // Transmitter mode as the driver runs it: a bounded beacon loop with BusyBox's usleep.
    const std::vector<uint8_t> beacon(50, 0x80);
    const std::string loop =
        "wl -i eth6 5g_rate -v 0 -s 1 && (n=0; while [ $n -lt 5 ]; do nexutil -I eth6 -s505 -b "
        "-l 50 -v " +
        emulator::base64Encode(beacon.data(), beacon.size()) +
        " || exit 1; usleep 2000; n=$((n+1)); done)";
    r = run(shell("PATH=" + bin + ":/usr/bin:/bin sh -c '" + loop + "'"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    r = run(shell(bin + "emulator-ctl status"));
    EXPECT_NE(r.output.find("\"rate\": \"-v 0 -s 1\", \"frames_injected\": 5"), std::string::npos)
        << r.output;

    r = run(shell(bin + "emulator-ctl stop"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(emu.wait(5), 0) << emu.err();
    EXPECT_NE(emu.out().find("\"stop_reason\": \"stop requested\""), std::string::npos)
        << emu.out();
    EXPECT_TRUE(std::filesystem::exists(state + "/summary.json"));
    // The emulator is gone: a shim now fails like ssh to an unreachable host.
    r = run(shell(bin + "wl -i eth6 chanspec"));
    EXPECT_EQ(r.exitCode, 255) << r.output;
}

TEST(EmulatorCli, SigtermStopsWithASummaryAndDurationBoundsTheRun)
{
    test::TempDir tmp;
    test::UdpReceiver rx;
    {
        EmulatorProcess emu(
            tmp, "--scenario " + writeScenario(tmp) + " --port " + std::to_string(rx.port()) +
                     " --state-dir " + tmp.file("a") + " --preconfigured 155/80 --duration 20 -q");
        ASSERT_TRUE(emu.waitForSocket(tmp.file("a") + "/emulator.sock"));
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        ::kill(emu.pid(), SIGTERM);
        EXPECT_EQ(emu.wait(5), 0);
        EXPECT_NE(emu.out().find("\"datagrams_sent\": "), std::string::npos) << emu.out();
        // Everything it says it sent arrived (loopback), however much that was.
        const auto sent = test::jsonCounter(emu.out(), "datagrams_sent");
        EXPECT_GT(sent, 0u);
        rx.waitQuiet();
        EXPECT_EQ(rx.count(), sent);
    }
    const auto t0 = test::Clock::now();
    const auto r =
        run(emulatorProgram() + " --scenario " + writeScenario(tmp) + " --port " +
            std::to_string(rx.port()) + " --state-dir " + tmp.file("b") +
            " --preconfigured 155/80 --duration 0.5 -q");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_LT(test::secondsSince(t0), 3.0);
    EXPECT_NE(r.output.find("duration reached"), std::string::npos);
}

namespace
{
/** The datagrams one emulator run sent (its --record-sent capture), in order. */
std::vector<std::vector<uint8_t>> sentDatagrams(
    const test::TempDir& tmp, const test::UdpReceiver& rx, const std::string& name,
    const std::string& seeds, std::string* output = nullptr)
{
    const std::string pcap = tmp.file(name + ".pcap");
    // Bounded by the datagram count, not by time: the same datagrams on any machine.
    const auto r =
        run(emulatorProgram() + " --scenario " + writeScenario(tmp) + " --port " +
            std::to_string(rx.port()) + " --state-dir " + tmp.file(name) +
            " --preconfigured 155/80 --speed 10 --duration 60 --max-datagrams 600 --loss 0.3 "
            "--record-sent " +
            pcap + " -q " + seeds);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("max datagrams reached"), std::string::npos) << r.output;
    if (output) *output = r.output;
    std::vector<std::vector<uint8_t>> out;
    PcapReader reader(pcap, rx.port());
    for (PcapUdpDatagram d; reader.next(d);)
        out.emplace_back(d.payload, d.payload + d.payloadLength);
    return out;
}

/** The CSI part of each datagram (after the 18-byte Nexmon header). */
std::set<std::vector<uint8_t>> csiOf(const std::vector<std::vector<uint8_t>>& datagrams)
{
    std::set<std::vector<uint8_t>> out;
    for (const auto& d : datagrams)
        if (d.size() > nexmon::kHeaderBytes)
            out.emplace(d.begin() + long(nexmon::kHeaderBytes), d.end());
    return out;
}

/** TUM rows (t x y ...), comments skipped. */
std::vector<std::vector<double>> readTum(const std::string& path)
{
    std::vector<std::vector<double>> rows;
    std::ifstream f(path);
    for (std::string line; std::getline(f, line);)
    {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream ss(line);
        std::vector<double> v;
        for (double x; ss >> x;) v.push_back(x);
        if (v.size() == 8) rows.push_back(v);
    }
    return rows;
}

size_t commonCount(const std::set<std::vector<uint8_t>>& a, const std::set<std::vector<uint8_t>>& b)
{
    size_t n = 0;
    for (const auto& x : a) n += b.count(x);
    return n;
}
}  // namespace

TEST(EmulatorCli, ScenarioSeedSetsTheWorldFaultSeedTheFaults)
{
    // The scenario file says `seed: 3`. --scenario-seed replaces it (other phases, other CSI);
    // --fault-seed only changes which datagrams the 30 % loss takes; --seed is the old name of
    // --fault-seed and says so.
    test::TempDir tmp;
    test::UdpReceiver rx;
    const auto a = sentDatagrams(tmp, rx, "a", "--scenario-seed 3 --fault-seed 1");
    const auto b = sentDatagrams(tmp, rx, "b", "--scenario-seed 3 --fault-seed 2");
    const auto c = sentDatagrams(tmp, rx, "c", "--scenario-seed 4 --fault-seed 1");
    std::string oldNameOutput;
    const auto d = sentDatagrams(tmp, rx, "d", "--seed 2", &oldNameOutput);
    const auto e = sentDatagrams(tmp, rx, "e", "--fault-seed 1");
    ASSERT_EQ(a.size(), 600u);
    ASSERT_EQ(b.size(), 600u);
    ASSERT_EQ(c.size(), 600u);

    // Same world, other faults: not the same datagrams, but every frame both sent is the same.
    EXPECT_NE(a, b);
    const auto csiA = csiOf(a), csiB = csiOf(b), csiC = csiOf(c);
    EXPECT_EQ(csiA.size(), a.size());  // every datagram's CSI is its own (noise)
    EXPECT_GT(commonCount(csiA, csiB), a.size() / 3) << "the same scenario seed, other CSI";
    // Another world: none of its CSI is the first world's.
    EXPECT_EQ(commonCount(csiA, csiC), 0u) << "another scenario seed, the same CSI";

    // --seed N = --fault-seed N (with the file's scenario seed), with a note naming both.
    EXPECT_EQ(d, b);
    EXPECT_NE(oldNameOutput.find("--seed is the old name of --fault-seed"), std::string::npos)
        << oldNameOutput;
    EXPECT_NE(oldNameOutput.find("--scenario-seed"), std::string::npos) << oldNameOutput;
    // Without --scenario-seed: the file's `seed: 3`.
    EXPECT_EQ(e, a);
    EXPECT_NE(
        test::readFile(tmp.file("a") + "/summary.json").find("\"scenario_seed\": 3"),
        std::string::npos);
    EXPECT_NE(
        test::readFile(tmp.file("c") + "/summary.json").find("\"scenario_seed\": 4"),
        std::string::npos);

    // The help tells them apart.
    const auto help = run(emulatorProgram() + " --help").output;
    for (const char* flag : {"--scenario-seed", "--fault-seed", "--truth-dir"})
        EXPECT_NE(help.find(flag), std::string::npos) << flag;
    EXPECT_NE(help.find("Old name of --fault-seed"), std::string::npos) << help;

    // Both names of the fault seed at once, or a scenario seed for a capture: refused.
    auto r =
        run(emulatorProgram() + " --scenario " + writeScenario(tmp) +
            " --seed 2 --fault-seed 2 --duration 1 -q --state-dir " + tmp.file("f"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--fault-seed"), std::string::npos) << r.output;
    r =
        run(emulatorProgram() + " --replay " + tmp.file("a.pcap") +
            " --scenario-seed 2 --duration 1 -q --state-dir " + tmp.file("g"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--scenario-seed needs --scenario"), std::string::npos) << r.output;
}

TEST(EmulatorCli, WritesTheTruthOnTheReceiversClock)
{
    // A driving robot (share/scenarios/kidnapped.yaml). STATE_DIR/truth/trajectory_tum.txt is
    // stamped with unix time: every datagram arrives within it, and its poses are wifi-sim's
    // (same scenario seed) at the same time since the start, so no shift is needed to score.
    test::TempDir tmp;
    test::UdpReceiver rx;
    const double rxStartUnix = mrpt::Clock::toDouble(mrpt::Clock::now());  // rx's time 0
    const double startUnix = mrpt::Clock::toDouble(mrpt::Clock::now());
    const auto r =
        run(emulatorProgram() + " --scenario " + test::sourceDir() +
            "/share/scenarios/kidnapped.yaml --scenario-seed 9 --port " +
            std::to_string(rx.port()) + " --state-dir " + tmp.file("s") +
            " --preconfigured 155/80 --speed 4 --duration 60 --max-datagrams 2000 -q");
    const double endUnix = mrpt::Clock::toDouble(mrpt::Clock::now());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    rx.waitQuiet();
    const auto truth = readTum(tmp.file("s/truth/trajectory_tum.txt"));
    ASSERT_GT(truth.size(), 10u);
    EXPECT_GE(truth.front()[0], startUnix);
    EXPECT_LE(truth.back()[0], endUnix);
    // --speed 4: 4 simulated seconds per second of the receiver's clock.
    EXPECT_NEAR(truth[1][0] - truth[0][0], 0.01 / 4, 1e-6);
    // Every datagram arrived while the robot was on the truth's time span (arrival: the
    // receiver's steady clock from its start, put on unix time; ms apart).
    const auto received = rx.snapshot();
    ASSERT_EQ(received.size(), 2000u);
    for (const auto& d : received)
    {
        ASSERT_GE(rxStartUnix + d.time_s, truth.front()[0] - 0.05);
        ASSERT_LE(rxStartUnix + d.time_s, truth.back()[0] + 0.05);
    }
    EXPECT_NE(test::readFile(tmp.file("s/truth/transmitters.yaml")).find("ap-"), std::string::npos);

    const auto sim =
        run(test::binDir() + "/wifi-sim " + test::sourceDir() + "/share" +
            "/scenarios/kidnapped.yaml /dev/null -q -s 9 -d 30 -t " + tmp.file("sim"));
    ASSERT_EQ(sim.exitCode, 0) << sim.output;
    const auto simTruth = readTum(tmp.file("sim/trajectory_tum.txt"));
    size_t compared = 0;
    for (size_t i = 0; i < truth.size() && i < simTruth.size(); ++i, ++compared)
    {
        ASSERT_NEAR((truth[i][0] - truth[0][0]) * 4, simTruth[i][0] - simTruth[0][0], 1e-4) << i;
        ASSERT_NEAR(truth[i][1], simTruth[i][1], 1e-5) << i;
        ASSERT_NEAR(truth[i][2], simTruth[i][2], 1e-5) << i;
    }
    EXPECT_GT(compared, 10u);
}
