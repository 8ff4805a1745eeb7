/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <arpa/inet.h>
#include <fcntl.h>
#include <mrpt_wifi/emulator/LoopbackUdp.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace mrpt_wifi::emulator
{
std::string LoopbackDestination::asString() const
{
    return (family == AF_INET6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

LoopbackDestination loopbackDestination(const std::string& hostIn, uint16_t port)
{
    if (port == 0) throw std::invalid_argument("destination port 0 is not valid");
    const std::string host = hostIn == "localhost" ? "127.0.0.1" : hostIn;
    LoopbackDestination d;
    d.port = port;
    in_addr v4{};
    in6_addr v6{};
    if (inet_pton(AF_INET, host.c_str(), &v4) == 1)
    {
        if ((ntohl(v4.s_addr) >> 24) != 127)
            throw std::invalid_argument(
                "refusing destination " + hostIn +
                ": the emulator only sends to loopback (127.0.0.0/8 or ::1), never to a LAN or "
                "broadcast address");
        auto* sa = reinterpret_cast<sockaddr_in*>(&d.address);
        sa->sin_family = AF_INET;
        sa->sin_port = htons(port);
        sa->sin_addr = v4;
        d.addressLength = sizeof(sockaddr_in);
        d.family = AF_INET;
    }
    else if (inet_pton(AF_INET6, host.c_str(), &v6) == 1)
    {
        if (!IN6_IS_ADDR_LOOPBACK(&v6))
            throw std::invalid_argument(
                "refusing destination " + hostIn +
                ": the only IPv6 destination allowed is the loopback address ::1");
        auto* sa = reinterpret_cast<sockaddr_in6*>(&d.address);
        sa->sin6_family = AF_INET6;
        sa->sin6_port = htons(port);
        sa->sin6_addr = v6;
        d.addressLength = sizeof(sockaddr_in6);
        d.family = AF_INET6;
    }
    else
        throw std::invalid_argument(
            "refusing destination '" + hostIn +
            "': give a numeric loopback address (127.0.0.1, ::1) or 'localhost'");
    char text[INET6_ADDRSTRLEN] = {};
    inet_ntop(
        d.family,
        d.family == AF_INET ? static_cast<const void*>(&v4) : static_cast<const void*>(&v6), text,
        sizeof(text));
    d.host = text;
    return d;
}

LoopbackUdpSender::LoopbackUdpSender(const LoopbackDestination& dest) : dest_(dest)
{
    // Re-check: a hand-built LoopbackDestination must not bypass the loopback rule.
    const LoopbackDestination checked = loopbackDestination(dest.host, dest.port);
    if (checked.family != dest.family)
        throw std::invalid_argument("inconsistent destination " + dest.asString());
    dest_ = checked;
    fd_ = ::socket(dest_.family, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0)
        throw std::runtime_error(std::string("cannot create UDP socket: ") + std::strerror(errno));
    const int sendBuffer = 4 << 20;  // bursts of 16 datagrams × several transmitters
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &sendBuffer, sizeof(sendBuffer));
}

LoopbackUdpSender::~LoopbackUdpSender()
{
    if (fd_ >= 0) ::close(fd_);
}

bool LoopbackUdpSender::send(const uint8_t* data, size_t len)
{
    for (int attempt = 0; attempt < 2; ++attempt)
    {
        const ssize_t n = ::sendto(
            fd_, data, len, MSG_NOSIGNAL, reinterpret_cast<const sockaddr*>(&dest_.address),
            dest_.addressLength);
        if (n == ssize_t(len))
        {
            ++sent_;
            bytes_ += len;
            return true;
        }
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && attempt == 0)
        {
            pollfd p{fd_, POLLOUT, 0};
            ::poll(&p, 1, int(maxBlock_s * 1000));
            continue;
        }
        lastError_ = n < 0 ? std::strerror(errno) : "short send";
        break;
    }
    ++errors_;
    return false;
}

}  // namespace mrpt_wifi::emulator
