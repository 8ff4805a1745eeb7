/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <arpa/inet.h>
#include <mrpt_wifi/sensor/UdpCsiReceiver.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
constexpr size_t kMaxDatagram = 65536;

std::runtime_error socketError(const UdpCsiReceiverOptions& o, const std::string& what)
{
    return std::runtime_error(
        "UDP " + o.bindAddress + ":" + std::to_string(o.port) + ": " + what + ": " +
        std::strerror(errno));
}
}  // namespace

UdpCsiReceiver::UdpCsiReceiver(const UdpCsiReceiverOptions& options) : buffer_(kMaxDatagram)
{
    sockaddr_storage addr{};
    socklen_t addrLen = 0;
    int family = AF_INET;
    if (auto* a4 = reinterpret_cast<sockaddr_in*>(&addr);
        inet_pton(AF_INET, options.bindAddress.c_str(), &a4->sin_addr) == 1)
    {
        a4->sin_family = AF_INET;
        a4->sin_port = htons(options.port);
        addrLen = sizeof(sockaddr_in);
    }
    else if (auto* a6 = reinterpret_cast<sockaddr_in6*>(&addr);
             inet_pton(AF_INET6, options.bindAddress.c_str(), &a6->sin6_addr) == 1)
    {
        family = AF_INET6;
        a6->sin6_family = AF_INET6;
        a6->sin6_port = htons(options.port);
        addrLen = sizeof(sockaddr_in6);
    }
    else
        throw std::runtime_error(
            "UDP bind address '" + options.bindAddress + "' is not an IPv4/IPv6 literal");

    fd_ = ::socket(family, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw socketError(options, "socket()");
    const int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &options.receiveBufferBytes, sizeof(int));
    ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof(one));
    ::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof(one));
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), addrLen) != 0)
    {
        const auto err = socketError(options, "bind()");
        ::close(fd_);
        throw err;
    }
    socklen_t len = sizeof(addr);
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    boundPort_ = ntohs(
        family == AF_INET ? reinterpret_cast<sockaddr_in*>(&addr)->sin_port
                          : reinterpret_cast<sockaddr_in6*>(&addr)->sin6_port);
    len = sizeof(grantedBuffer_);
    ::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &grantedBuffer_, &len);
}

UdpCsiReceiver::~UdpCsiReceiver()
{
    if (fd_ >= 0) ::close(fd_);
}

size_t UdpCsiReceiver::receive(
    const OnDatagram& onDatagram, std::chrono::milliseconds wait, size_t maxDatagrams)
{
    pollfd pfd{fd_, POLLIN, 0};
    if (::poll(&pfd, 1, int(wait.count())) <= 0) return 0;

    size_t delivered = 0;
    alignas(cmsghdr) uint8_t control[256];
    sockaddr_storage source{};
    while (delivered < maxDatagrams)
    {
        iovec iov{buffer_.data(), buffer_.size()};
        msghdr msg{};
        msg.msg_name = &source;
        msg.msg_namelen = sizeof(source);
        msg.msg_iov = &iov;
        msg.msg_iovlen = 1;
        msg.msg_control = control;
        msg.msg_controllen = sizeof(control);
        const ssize_t n = ::recvmsg(fd_, &msg, 0);
        if (n < 0)
        {
            if (errno == EINTR) continue;
            break;  // EAGAIN: drained
        }
        auto arrival = mrpt::Clock::now();
        for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c))
        {
            if (c->cmsg_level != SOL_SOCKET) continue;
            if (c->cmsg_type == SO_TIMESTAMPNS)
            {
                timespec ts;
                std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
                arrival = mrpt::Clock::fromDouble(double(ts.tv_sec)) +
                          std::chrono::duration_cast<mrpt::Clock::duration>(
                              std::chrono::nanoseconds(ts.tv_nsec));
            }
            else if (c->cmsg_type == SO_RXQ_OVFL)
            {
                uint32_t drops;
                std::memcpy(&drops, CMSG_DATA(c), sizeof(drops));
                kernelDrops_ = drops;
            }
        }
        // Convert the source address to text only when it changes (one router, usually).
        const auto* key = reinterpret_cast<const uint8_t*>(&source);
        if (lastSourceKey_.size() != msg.msg_namelen ||
            std::memcmp(lastSourceKey_.data(), key, msg.msg_namelen) != 0)
        {
            lastSourceKey_.assign(key, key + msg.msg_namelen);
            char text[INET6_ADDRSTRLEN] = {0};
            if (source.ss_family == AF_INET)
                inet_ntop(
                    AF_INET, &reinterpret_cast<sockaddr_in*>(&source)->sin_addr, text,
                    sizeof(text));
            else
                inet_ntop(
                    AF_INET6, &reinterpret_cast<sockaddr_in6*>(&source)->sin6_addr, text,
                    sizeof(text));
            lastSourceText_ = text;
        }
        onDatagram(buffer_.data(), size_t(n), arrival, lastSourceText_);
        ++delivered;
    }
    return delivered;
}

}  // namespace mrpt_wifi
