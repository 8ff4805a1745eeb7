/* mrpt_wifi — recording unattended, as share/systemd/mrpt-wifi-record.service runs it: no
 * terminal (stdin /dev/null, its own session), stopped by the unit's KillSignal after the
 * emulator sent a known number of frames. The rawlog must be complete (a valid gzip stream to
 * its end) and hold every frame the emulator reports it sent. */
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <regex>
#include <thread>

#include "EmulatorProcess.h"
#include "GrabberRun.h"
#include "SshdFixture.h"

using namespace mrpt_wifi;

namespace
{
const std::string kUnit = test::sourceDir() + "/share/systemd/mrpt-wifi-record.service";

/** `Key=value` of the unit file ("" when absent). */
std::string unitValue(const std::string& key)
{
    std::smatch m;
    const std::string text = test::readFile(kUnit);
    if (!std::regex_search(text, m, std::regex("(^|\n)" + key + "=([^\n]*)"))) return "";
    return m[2];
}

/** A program started as systemd starts a service: stdin /dev/null, no controlling terminal
 *  (a session of its own), stdout+stderr to a file, in `dir`. */
class ServiceProcess
{
public:
    ServiceProcess(const std::vector<std::string>& argv, const std::string& dir, std::string log)
        : log_(std::move(log))
    {
        pid_ = ::fork();
        if (pid_ == 0)
        {
            ::setsid();
            const int in = ::open("/dev/null", O_RDONLY);
            const int out = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            ::dup2(in, STDIN_FILENO);
            ::dup2(out, STDOUT_FILENO);
            ::dup2(out, STDERR_FILENO);
            if (::chdir(dir.c_str()) != 0) ::_exit(126);
            std::vector<char*> args;
            for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
            args.push_back(nullptr);
            ::execv(args[0], args.data());
            ::_exit(127);
        }
    }
    ~ServiceProcess()
    {
        if (pid_ > 0) ::kill(pid_, SIGKILL), ::waitpid(pid_, nullptr, 0);
    }
    /** Whether it is still running after `wait` (polled). */
    bool runningAfter(std::chrono::milliseconds wait)
    {
        const auto until = std::chrono::steady_clock::now() + wait;
        while (std::chrono::steady_clock::now() < until)
        {
            if (exited()) return false;
            std::this_thread::sleep_for(std::chrono::milliseconds(25));
        }
        return !exited();
    }
    /** Sends `sig`, then waits at most `limit` for the exit status (-1: still running). */
    int stop(int sig, std::chrono::seconds limit)
    {
        if (pid_ > 0) ::kill(pid_, sig);
        const auto until = std::chrono::steady_clock::now() + limit;
        while (!exited() && std::chrono::steady_clock::now() < until)
            std::this_thread::sleep_for(std::chrono::milliseconds(25));
        return exited() ? status_ : -1;
    }
    std::string log() const { return test::readFile(log_); }

private:
    pid_t pid_ = -1;
    int status_ = -1;
    std::string log_;
    bool exited()
    {
        if (pid_ <= 0) return true;
        int st = 0;
        if (::waitpid(pid_, &st, WNOHANG) != pid_) return false;
        status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        pid_ = -1;
        return true;
    }
};

std::vector<std::string> rawlogsIn(const test::TempDir& dir)
{
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(dir.path()))
        if (e.path().extension() == ".rawlog") files.push_back(e.path().string());
    return files;
}

/** csi_receiver.ini for the emulator on 127.0.0.1:port (listening only). */
std::string receiverIni(const test::TempDir& tmp, uint16_t port)
{
    return test::deriveGrabberIni(
        "csi_receiver.ini",
        {{"udp_port", std::to_string(port)},
         {"udp_bind_address", "127.0.0.1"},
         {"router_address", ""},
         {"router_control", "false"},
         {"scan_period", "0"},
         {"status_period", "1"}},
        tmp.file("receiver.ini"));
}
}  // namespace

TEST(UnattendedRecording, TheUnitRunsMrptWifiRecordWithoutATerminalAndStopsItWithSigterm)
{
    // What the test below reproduces is what the unit file says.
    EXPECT_NE(unitValue("ExecStart").find("/mrpt-wifi-record "), std::string::npos)
        << unitValue("ExecStart");
    EXPECT_EQ(unitValue("StandardInput"), "null");
    EXPECT_EQ(unitValue("KillSignal"), "SIGTERM");
    EXPECT_EQ(unitValue("KillMode"), "mixed");
}

TEST(UnattendedRecording, SigtermAfterAKnownNumberOfFramesKeepsEveryFrame)
{
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    const auto ini = receiverIni(tmp, port);
    ServiceProcess rec(
        {test::binDir() + "/mrpt-wifi-record", ini}, tmp.path().string(), tmp.file("rec.log"));
    ASSERT_TRUE(test::waitForUdpListener(port, std::chrono::seconds(30))) << rec.log();
    // Its stdin is at end of file from the start: it must keep recording regardless.
    ASSERT_TRUE(rec.runningAfter(std::chrono::milliseconds(500))) << rec.log();

    // 60 frames of 16 datagrams (4 cores x 4 streams, preconfigured), then the emulator stops by
    // itself; how many frames that was is its own count, not the clock's.
    {
        test::EmulatorProcess emu(
            {"--scenario", test::sourceDir() + "/share/scenarios/kidnapped.yaml", "--preconfigured",
             "155/80", "--max-datagrams", "960", "--record-sent", tmp.file("sent.pcap")},
            port, 60);
        ASSERT_TRUE(emu.ready()) << emu.log();
        const std::string summary = test::emulatorSummaryJson(emu.stateDir(), 60);
        std::smatch m;
        ASSERT_TRUE(std::regex_search(summary, m, std::regex("\"frames_emitted\": *([0-9]+)")))
            << summary;
        const size_t emitted = std::stoul(m[1]);
        ASSERT_GT(emitted, 0u);
        ASSERT_TRUE(std::regex_search(summary, m, std::regex("\"datagrams_sent\": *([0-9]+)")));
        EXPECT_EQ(std::stoul(m[1]), 960u);

        // Stopped as `systemctl stop` does: the unit's KillSignal to the main process.
        const int status = rec.stop(SIGTERM, std::chrono::seconds(60));
        ASSERT_EQ(status, 0) << rec.log();
        EXPECT_NE(rec.log().find("stopped (signal"), std::string::npos) << rec.log();

        const auto files = rawlogsIn(tmp);
        ASSERT_EQ(files.size(), 1u);
        // A complete gzip stream: closed, not cut off.
        const auto gz = test::run("gzip -t " + files[0]);
        EXPECT_EQ(gz.exitCode, 0) << gz.output;
        std::vector<CObservationWiFiCSI::Ptr> frames;
        for (const auto& o : test::readRawlog(files[0]))
            if (auto f = std::dynamic_pointer_cast<CObservationWiFiCSI>(o)) frames.push_back(f);
        EXPECT_EQ(frames.size(), emitted) << rec.log();
        // ... and they are the frames sent: none missing, none invented.
        const auto sent = test::decodeSentFrames(tmp.file("sent.pcap"), port);
        EXPECT_EQ(sent.size(), emitted);
        const auto c = test::compareWithSent(frames, sent);
        EXPECT_EQ(c.missing, 0u);
        EXPECT_EQ(c.neverSent, 0u);
        EXPECT_EQ(c.firstRecorded, 0u);
        EXPECT_EQ(c.sentInSpan, sent.size());
        EXPECT_NE(rec.log().find(std::to_string(emitted) + " objects written"), std::string::npos)
            << rec.log();
    }
}

TEST(UnattendedRecording, DebiansRawlogGrabberStopsByItselfWithoutATerminal)
{
    // Why mrpt-wifi-record exists (docs/troubleshooting.md): MRPT 2.5.8's rawlog-grabber ends
    // its loop when stdin is readable, and /dev/null always is. If this starts failing, a newer
    // MRPT runs unattended and the documentation should say so.
    const auto which = test::run("command -v rawlog-grabber");
    if (which.exitCode != 0) GTEST_SKIP() << "rawlog-grabber not installed (Debian's mrpt-apps)";
    const std::string program = which.output.substr(0, which.output.find('\n'));
    test::TempDir tmp;
    const uint16_t port = test::freeLoopbackPort(SOCK_DGRAM);
    const auto ini = receiverIni(tmp, port);
    ServiceProcess grabber(
        {program, "-p", test::libDir() + "/libmrpt_wifi_sensor.so", ini}, tmp.path().string(),
        tmp.file("grabber.log"));
    // Generous bound: it ends at its first loop turn, well under a second.
    EXPECT_FALSE(grabber.runningAfter(std::chrono::seconds(30))) << grabber.log();
    EXPECT_NE(grabber.log().find("Press any key"), std::string::npos) << grabber.log();
}
