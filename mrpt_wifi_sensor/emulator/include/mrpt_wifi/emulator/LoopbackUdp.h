/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <netinet/in.h>
#include <sys/socket.h>

#include <cstdint>
#include <string>

namespace mrpt_wifi::emulator
{
/** A validated UDP destination on the loopback interface. */
struct LoopbackDestination
{
    sockaddr_storage address{};
    socklen_t addressLength = 0;
    int family = AF_INET;
    std::string host;  //!< numeric text
    uint16_t port = 0;

    std::string asString() const;  //!< "127.0.0.1:5500" or "[::1]:5500"
};

/** Parses and checks a destination. Only numeric IPv4 addresses in 127.0.0.0/8, IPv6 "::1"
 * and the name "localhost" (= 127.0.0.1) are accepted: the emulator must never put CSI on a LAN
 * or broadcast it. Throws std::invalid_argument with the reason otherwise (and for port 0). */
LoopbackDestination loopbackDestination(const std::string& host, uint16_t port);

/** Sends datagrams to one loopback destination with a non-blocking socket (never
 * SO_BROADCAST). When the socket buffer is full it waits at most maxBlock_s for room, then
 * counts the datagram as a send error rather than stalling the emulator. */
class LoopbackUdpSender
{
public:
    explicit LoopbackUdpSender(const LoopbackDestination& dest);
    ~LoopbackUdpSender();
    LoopbackUdpSender(const LoopbackUdpSender&) = delete;
    LoopbackUdpSender& operator=(const LoopbackUdpSender&) = delete;

    bool send(const uint8_t* data, size_t len);

    const LoopbackDestination& destination() const { return dest_; }
    uint64_t datagramsSent() const { return sent_; }
    uint64_t bytesSent() const { return bytes_; }
    uint64_t sendErrors() const { return errors_; }
    const std::string& lastError() const { return lastError_; }

    double maxBlock_s = 0.05;

private:
    LoopbackDestination dest_;
    int fd_ = -1;
    uint64_t sent_ = 0, bytes_ = 0, errors_ = 0;
    std::string lastError_;
};

}  // namespace mrpt_wifi::emulator
