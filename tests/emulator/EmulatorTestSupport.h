/* mrpt_wifi — helpers for the RT-AC86U emulator tests: a loopback UDP receiver, a small
 * scenario, an emulator running in a thread. Everything on 127.0.0.1, bounded in time. */
#pragma once

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <mrpt_wifi/emulator/Emulator.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <mrpt_wifi/sim/Scenario.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "TestSupport.h"

namespace mrpt_wifi::test
{
using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

/** One datagram as a receiver saw it. */
struct Received
{
    double time_s = 0;  //!< arrival, seconds since the receiver started
    std::vector<uint8_t> bytes;
};

/** A UDP socket on 127.0.0.1 (ephemeral port) drained by a background thread. */
class UdpReceiver
{
public:
    UdpReceiver() : start_(Clock::now())
    {
        fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
        const int buf = 16 << 20;
        ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buf, sizeof(buf));
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0)
            throw std::runtime_error("bind 127.0.0.1 failed");
        socklen_t len = sizeof(a);
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
        port_ = ntohs(a.sin_port);
        thread_ = std::thread([this] { loop(); });
    }
    ~UdpReceiver()
    {
        stop_ = true;
        thread_.join();
        ::close(fd_);
    }
    uint16_t port() const { return port_; }
    double now() const { return secondsSince(start_); }
    std::vector<Received> snapshot() const
    {
        std::lock_guard<std::mutex> lock(mutex_);
        return received_;
    }
    size_t count() const
    {
        std::lock_guard<std::mutex> lock(mutex_);
        return received_.size();
    }
    /** Waits until nothing arrives for `quiet_s` (at most max_s). */
    void waitQuiet(double quiet_s = 0.15, double max_s = 3.0) const
    {
        const auto t0 = Clock::now();
        size_t last = count();
        auto lastChange = Clock::now();
        while (secondsSince(t0) < max_s)
        {
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            const size_t n = count();
            if (n != last)
            {
                last = n;
                lastChange = Clock::now();
            }
            else if (secondsSince(lastChange) >= quiet_s)
                return;
        }
    }

private:
    void loop()
    {
        std::vector<uint8_t> buf(65536);
        while (!stop_)
        {
            pollfd p{fd_, POLLIN, 0};
            if (::poll(&p, 1, 20) <= 0) continue;
            for (;;)
            {
                const ssize_t n = ::recv(fd_, buf.data(), buf.size(), MSG_DONTWAIT);
                if (n < 0) break;
                Received r;
                r.time_s = now();
                r.bytes.assign(buf.begin(), buf.begin() + n);
                std::lock_guard<std::mutex> lock(mutex_);
                received_.push_back(std::move(r));
            }
        }
    }

    Clock::time_point start_;
    int fd_ = -1;
    uint16_t port_ = 0;
    std::atomic<bool> stop_{false};
    std::thread thread_;
    mutable std::mutex mutex_;
    std::vector<Received> received_;
};

/** Four transmitters in open space around a static robot: ap-a (2 streams), ap-b and ap-d on
 * 155/80, ap-c on 42/80. ap-a and ap-b share their first two MAC bytes (hardware filter quirk),
 * ap-d doesn't. */
inline sim::Scenario emulatorTestScenario()
{
    using mrpt::math::TPoint2D;
    sim::Scenario sc;
    sc.name = "emulator-test";
    sc.duration_s = 120;
    sc.seed = 11;
    sc.receiver.array.name = "rt-ac86u";
    sc.receiver.array.elements = {
        TPoint2D(0, 0), TPoint2D(0, 0.052), TPoint2D(0, 0.026), TPoint2D(0, 0.078)};
    sc.motion.type = sim::MotionType::Static;
    sc.odometry.enabled = false;
    auto tx =
        [](const char* name, const char* mac, double x, double y, const char* ch, unsigned streams)
    {
        sim::TransmitterSpec t;
        t.name = name;
        t.mac = MacAddress::fromString(mac);
        t.pose = {x, y, M_PI};
        t.chanspec = Chanspec::fromString(ch);
        t.streams = streams;
        t.array.name = "two";
        t.array.elements = {TPoint2D(0, 0), TPoint2D(0, 0.026)};
        t.frameRate_Hz = 100;
        t.firstSequenceNumber = 100;
        return t;
    };
    sc.transmitters = {
        tx("ap-a", "02:aa:00:00:00:01", 4, 1, "155/80", 2),
        tx("ap-b", "02:aa:00:00:00:02", 3, -2, "155/80", 1),
        tx("ap-d", "02:cc:00:00:00:03", -3, 2, "155/80", 1),
        tx("ap-c", "02:bb:00:00:00:04", 2, 3, "42/80", 1)};
    return sc;
}

/** Emulator options for a test: the scenario above, to `port`, control socket in `stateDir`. */
inline emulator::EmulatorOptions testOptions(uint16_t port, const std::string& stateDir)
{
    emulator::EmulatorOptions o;
    o.scenario = emulatorTestScenario();
    o.port = port;
    o.stateDir = stateDir;
    o.duration_s = 20;  // safety bound; tests stop it earlier
    return o;
}

/** An Emulator running in its own thread, driven through its Unix socket like the shims. */
class RunningEmulator
{
public:
    explicit RunningEmulator(const emulator::EmulatorOptions& o)
        : emulator_(std::make_unique<emulator::Emulator>(o))
    {
        thread_ = std::thread([this] { reason_ = emulator_->run(); });
    }
    ~RunningEmulator() { stop(); }
    emulator::ToolResult call(const emulator::Argv& argv)
    {
        return emulator::callEmulator(emulator_->socketPath(), argv, 5.0);
    }
    /** `wl ...` style call that must succeed. */
    void ok(const emulator::Argv& argv)
    {
        const auto r = call(argv);
        ASSERT_EQ(r.exitCode, 0) << argv[0] << " " << (argv.size() > 1 ? argv[1] : "") << ": "
                                 << r.err;
    }
    std::string status() { return call({"emulator-ctl", "status"}).out; }
    void stop()
    {
        if (!thread_.joinable()) return;
        emulator_->requestStop();
        thread_.join();
    }
    /** Waits for run() to end by itself (at most max_s). */
    bool waitEnd(double max_s)
    {
        const auto t0 = Clock::now();
        while (reason_ == emulator::StopReason::Running && secondsSince(t0) < max_s)
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        stop();
        return reason_ != emulator::StopReason::Running;
    }
    emulator::Emulator& get() { return *emulator_; }

private:
    std::unique_ptr<emulator::Emulator> emulator_;
    std::thread thread_;
    std::atomic<emulator::StopReason> reason_{emulator::StopReason::Running};
};

/** The configuration commands of WiROS for a channel (cores/streams as masks, optional MACs). */
inline void configureCsi(
    RunningEmulator& e, const std::string& chanspec, const std::string& cores = "0xf",
    const std::string& streams = "0xf", const std::string& macs = "")
{
    emulator::Argv mk{"makecsiparams", "-e", "1", "-c", chanspec, "-C", cores, "-N", streams};
    if (!macs.empty())
    {
        mk.push_back("-m");
        mk.push_back(macs);
    }
    const auto params = e.call(mk);
    ASSERT_EQ(params.exitCode, 0) << params.err;
    std::string b64 = params.out;
    while (!b64.empty() && b64.back() == '\n') b64.pop_back();
    e.ok({"wl", "-i", "eth6", "chanspec", chanspec});
    e.ok({"wl", "-i", "eth6", "monitor", "1"});
    e.ok({"nexutil", "-I", "eth6", "-s500", "-b", "-l34", "-v", b64});
}

/** A counter "name": N from a status JSON. */
inline uint64_t jsonCounter(const std::string& json, const std::string& name)
{
    std::smatch m;
    const std::regex re("\"" + name + "\": ([0-9]+)");
    if (!std::regex_search(json, m, re)) throw std::runtime_error("no counter " + name);
    return std::stoull(m[1]);
}

/** Header fields of a datagram the receiver got; false if the decoder rejects it. */
inline bool parse(const Received& r, nexmon::DatagramHeader& h)
{
    nexmon::RejectReason why;
    return nexmon::parseHeader(r.bytes.data(), r.bytes.size(), nexmon::FormatHint::Auto, h, why);
}

}  // namespace mrpt_wifi::test
