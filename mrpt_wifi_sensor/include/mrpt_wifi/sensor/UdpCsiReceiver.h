/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mrpt_wifi
{
struct UdpCsiReceiverOptions
{
    std::string bindAddress = "0.0.0.0";  //!< IPv4 or IPv6 literal
    uint16_t port = 5500;                 //!< 0: any free port (tests)
    /** SO_RCVBUF request: the router sends bursts of 16 datagrams per frame, and the control
     * path may keep the driver busy; the kernel doubles and caps it (net.core.rmem_max). */
    int receiveBufferBytes = 16 << 20;
};

/** The UDP data path: a non-blocking socket drained completely on every call.
 *
 * Each datagram is stamped with its kernel arrival time (SO_TIMESTAMPNS), so timestamps do not
 * depend on how often the caller polls; datagrams the kernel dropped for lack of buffer space
 * are counted (SO_RXQ_OVFL). */
class UdpCsiReceiver
{
public:
    /** Source of a datagram, as text ("10.10.10.10"). */
    using OnDatagram = std::function<void(
        const uint8_t* data, size_t len, mrpt::Clock::time_point arrival,
        const std::string& source)>;

    /** Opens and binds; throws std::runtime_error naming address, port and the OS error. */
    explicit UdpCsiReceiver(const UdpCsiReceiverOptions& options);
    ~UdpCsiReceiver();
    UdpCsiReceiver(const UdpCsiReceiver&) = delete;
    UdpCsiReceiver& operator=(const UdpCsiReceiver&) = delete;

    /** Waits up to `wait` for data, then delivers everything queued (at most `maxDatagrams`,
     * so one call can't starve the caller). Returns the number delivered. */
    size_t receive(
        const OnDatagram& onDatagram, std::chrono::milliseconds wait, size_t maxDatagrams = 200000);

    uint16_t boundPort() const { return boundPort_; }
    /** Datagrams the kernel dropped since the socket opened (receive buffer full). */
    uint64_t kernelDrops() const { return kernelDrops_; }
    /** Receive buffer the kernel actually granted [bytes]. */
    int receiveBufferBytes() const { return grantedBuffer_; }

private:
    int fd_ = -1;
    uint16_t boundPort_ = 0;
    int grantedBuffer_ = 0;
    uint64_t kernelDrops_ = 0;
    std::vector<uint8_t> buffer_;
    std::vector<uint8_t> lastSourceKey_;
    std::string lastSourceText_;
};

}  // namespace mrpt_wifi
