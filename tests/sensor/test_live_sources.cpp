/* Live CSI sources: an ESP32 on a serial port (played through a pseudo-terminal) and libpcap
 * live capture of Nexmon datagrams on the loopback interface (sent to 127.0.0.1 only; needs
 * CAP_NET_RAW, skipped without it). */
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>
#include <mrpt_wifi/sensor/CsiLiveSource.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <netinet/in.h>
#include <pty.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace std::chrono_literals;

namespace
{
std::string data(const std::string& rel)
{
    return test::sourceDir() + "/tests/data/" + rel;
}

/** A pseudo-terminal: the test writes to the master, the source reads the slave. */
struct Pty
{
    int master = -1, slave = -1;
    std::string slaveName;
    Pty()
    {
        char name[256] = {0};
        if (openpty(&master, &slave, name, nullptr, nullptr) == 0) slaveName = name;
    }
    ~Pty()
    {
        if (master >= 0) close(master);
        if (slave >= 0) close(slave);
    }
    void write(const std::string& s) const
    {
        for (size_t off = 0; off < s.size();)
        {
            const ssize_t n = ::write(master, s.data() + off, s.size() - off);
            if (n <= 0) break;
            off += size_t(n);
        }
    }
};

TEST(LiveSources, Esp32LinesOnASerialPortBecomeFrames)
{
    Pty pty;
    ASSERT_FALSE(pty.slaveName.empty()) << "openpty failed";
    CsiLiveSourceOptions o;
    o.baud = 115200;
    auto source = openLiveSource("serial:" + pty.slaveName, o);
    EXPECT_NE(source->describe().find(pty.slaveName), std::string::npos);

    const std::string lines = test::readFile(data("esp32/csi_data.csv"));
    // Boot chatter, a broken line, then the 8 recorded lines, split at awkward places.
    pty.write("I (312) wifi: boot\r\nCSI_DATA,1,2,3,[1 2\n");
    const size_t half = lines.size() / 2;
    std::vector<CObservationWiFiCSI::Ptr> frames;
    const auto sink = [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); };
    pty.write(lines.substr(0, half));
    source->poll({}, sink, 200ms);
    pty.write(lines.substr(half));
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (frames.size() < 8 && std::chrono::steady_clock::now() < deadline)
        source->poll({}, sink, 50ms);
    ASSERT_EQ(frames.size(), 8u);
    EXPECT_EQ(frames[0]->source, "esp32");
    EXPECT_EQ(frames[0]->transmitter.asString(), "70:3a:73:0c:6c:fb");
    EXPECT_EQ(source->stats().rejected, 1u);
    EXPECT_NE(source->stats().lastError.find("truncated"), std::string::npos)
        << source->stats().lastError;
}

TEST(LiveSources, MissingDevicesAndBadRatesAreNamed)
{
    CsiLiveSourceOptions o;
    try
    {
        openLiveSource("serial:/dev/no-such-tty", o);
        FAIL();
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find("/dev/no-such-tty"), std::string::npos);
    }
    o.baud = 12345;
    EXPECT_THROW(openLiveSource("serial:/dev/null", o), std::runtime_error);
    EXPECT_THROW(openLiveSource("bluetooth:x", {}), std::runtime_error);
    EXPECT_THROW(openLiveSource("interface:no-such-if0", {}), std::runtime_error);
}

TEST(LiveSources, CWiFiCSISensorRecordsAnEsp32OnASerialPort)
{
    Pty pty;
    ASSERT_FALSE(pty.slaveName.empty());
    mrpt::config::CConfigFileMemory cfg(
        "[CSI]\ndriver = CWiFiCSISensor\nsensorLabel = ESP32\nsource = serial:" + pty.slaveName +
        "\nserial_baud = 115200\nstatus_period = 0\n");
    CWiFiCSISensor sensor;
    sensor.loadConfig(cfg, "CSI");
    sensor.initialize();
    pty.write(test::readFile(data("esp32/csi_data.csv")));
    mrpt::hwdrivers::CGenericSensor::TListObservations got;
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (got.size() < 8 && std::chrono::steady_clock::now() < deadline)
    {
        sensor.doProcess();
        mrpt::hwdrivers::CGenericSensor::TListObservations more;
        sensor.getObservations(more);
        got.insert(more.begin(), more.end());
        std::this_thread::sleep_for(10ms);
    }
    ASSERT_EQ(got.size(), 8u);
    const auto csi = std::dynamic_pointer_cast<CObservationWiFiCSI>(got.begin()->second);
    ASSERT_TRUE(csi);
    EXPECT_EQ(csi->sensorLabel, "ESP32");
    EXPECT_EQ(csi->source, "esp32");
}

TEST(LiveSources, NexmonDatagramsCapturedOnLoopback)
{
    // Port chosen per process so parallel runs don't see each other's datagrams.
    const uint16_t port = uint16_t(40000 + getpid() % 20000);
    CsiLiveSourceOptions o;
    o.udpPort = port;
    std::unique_ptr<CsiLiveSource> source;
    try
    {
        source = openLiveSource("interface:lo", o);
    }
    catch (const std::exception& e)
    {
        GTEST_SKIP() << "no live capture on lo here (needs CAP_NET_RAW): " << e.what();
    }
    // The 4 datagrams of nexmon_csi's BCM4358 example, sent once to 127.0.0.1 (nobody listens:
    // the capture sees them on lo regardless).
    std::vector<std::vector<uint8_t>> datagrams;
    {
        PcapReader reader(data("nexmon/bcm4358-80mhz.pcap"));
        PcapUdpDatagram d;
        while (reader.next(d)) datagrams.emplace_back(d.payload, d.payload + d.payloadLength);
    }
    ASSERT_EQ(datagrams.size(), 4u);
    const int sock = socket(AF_INET, SOCK_DGRAM, 0);
    ASSERT_GE(sock, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    for (const auto& d : datagrams)
        sendto(sock, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
    close(sock);

    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiFrameAssembler assembler(
        CsiFrameAssemblerOptions{}, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); });
    size_t received = 0;
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (received < 4 && std::chrono::steady_clock::now() < deadline)
        source->poll(
            [&](const uint8_t* d, size_t n, mrpt::Clock::time_point t, const std::string& src)
            {
                ++received;
                EXPECT_EQ(src, "127.0.0.1");
                assembler.push(d, n, t, src);
            },
            {}, 50ms);
    assembler.flushAll();
    if (source->stats().packets == 0)
        GTEST_SKIP() << "the capture on lo saw no packet at all: this kernel (sandbox) does not "
                        "deliver loopback traffic to packet sockets";
    ASSERT_EQ(received, 4u);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0]->source, "bcm4358");
    EXPECT_TRUE(frames[0]->isComplete());
}
}  // namespace
