#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/UdpCsiReceiver.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <thread>

using namespace mrpt_wifi;

namespace
{
/** Sends `n` datagrams of `size` bytes to 127.0.0.1:port (loopback only). */
void sendLoopback(uint16_t port, int n, size_t size)
{
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(port);
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::vector<uint8_t> payload(size);
    for (int i = 0; i < n; ++i)
    {
        payload[0] = uint8_t(i);
        ::sendto(
            fd, payload.data(), payload.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to));
    }
    ::close(fd);
}
}  // namespace

TEST(UdpCsiReceiver, DrainsEverythingWithKernelTimestamps)
{
    UdpCsiReceiverOptions o;
    o.bindAddress = "127.0.0.1";
    o.port = 0;
    UdpCsiReceiver rx(o);
    ASSERT_NE(rx.boundPort(), 0);
    // The kernel turns packet timestamping on asynchronously when a socket first asks for it;
    // until then recvmsg stamps at read time. A long-lived receiver only sees that at start.
    sendLoopback(rx.boundPort(), 1, 64);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    rx.receive([](auto...) {}, std::chrono::milliseconds(100));
    const auto before = mrpt::Clock::now();
    sendLoopback(rx.boundPort(), 500, 1042);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // arrival ≠ read time
    const auto readStart = mrpt::Clock::now();
    std::vector<int> order;
    std::string source;
    double earliest_s = 1e300, latest_s = 0;
    const size_t n = rx.receive(
        [&](const uint8_t* d, size_t len, mrpt::Clock::time_point t, const std::string& src)
        {
            EXPECT_EQ(len, 1042u);
            order.push_back(d[0]);
            source = src;
            earliest_s = std::min(earliest_s, mrpt::Clock::toDouble(t));
            latest_s = std::max(latest_s, mrpt::Clock::toDouble(t));
        },
        std::chrono::milliseconds(100));
    EXPECT_EQ(n, 500u);  // one call drains them all
    EXPECT_EQ(source, "127.0.0.1");
    // Stamped when they arrived (after `before`), not when they were read 300 ms later.
    EXPECT_GE(earliest_s, mrpt::Clock::toDouble(before) - 1e-3);
    EXPECT_LE(latest_s, mrpt::Clock::toDouble(readStart) - 0.150)
        << "timestamps are the kernel's arrival times, not the read time";
    for (int i = 0; i < 500; ++i) ASSERT_EQ(order[size_t(i)], i % 256);
    EXPECT_EQ(rx.receive([](auto...) {}, std::chrono::milliseconds(10)), 0u);
}

TEST(UdpCsiReceiver, BadBindIsAClearError)
{
    UdpCsiReceiverOptions o;
    o.bindAddress = "not-an-address";
    EXPECT_THROW(UdpCsiReceiver{o}, std::runtime_error);
    // An address this host doesn't have (TEST-NET-1): bind fails; nothing is sent.
    o.bindAddress = "192.0.2.1";
    o.port = 5599;
    try
    {
        UdpCsiReceiver rx(o);
        FAIL() << "bound to an address this host doesn't have";
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find("192.0.2.1:5599"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("bind"), std::string::npos) << e.what();
    }
}
