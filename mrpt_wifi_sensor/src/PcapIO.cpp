/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <arpa/inet.h>
#include <mrpt/core/exceptions.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <pcap/pcap.h>

#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace mrpt_wifi
{
namespace
{
// Link types (pcap-linktype(7)); DLT_ names vary across libpcap versions, the numbers don't.
constexpr int kLinkEthernet = 1, kLinkRawA = 12, kLinkRawB = 101, kLinkLinuxSll = 113,
              kLinkLinuxSll2 = 276, kLinkIpv4 = 228, kLinkIpv6 = 229;
constexpr uint16_t kEtherIpv4 = 0x0800, kEtherIpv6 = 0x86DD, kEtherVlan = 0x8100,
                   kEtherQinQ = 0x88A8;
constexpr uint8_t kProtoUdp = 17;

inline uint16_t readBE16(const uint8_t* p)
{
    return uint16_t(p[0] << 8 | p[1]);
}

std::runtime_error fileError(const std::string& path, uint64_t offset, const std::string& what)
{
    return std::runtime_error(
        "pcap file '" + path + "' at byte offset " + std::to_string(offset) + ": " + what);
}
}  // namespace

struct PcapReader::Impl
{
    pcap_t* handle = nullptr;
    int linkType = 0;
    ~Impl()
    {
        if (handle) pcap_close(handle);
    }
};

PcapReader::PcapReader(const std::string& path, uint16_t udpPort)
    : impl_(std::make_unique<Impl>()), path_(path), udpPort_(udpPort)
{
    std::error_code ec;
    fileSize_ = std::filesystem::file_size(path, ec);
    if (ec) throw std::runtime_error("pcap file '" + path + "': " + ec.message());
    char err[PCAP_ERRBUF_SIZE] = {0};
    impl_->handle =
        pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, err);
    if (!impl_->handle)
        throw fileError(path, 0, std::string("not a readable pcap/pcapng capture: ") + err);
    impl_->linkType = pcap_datalink(impl_->handle);
    switch (impl_->linkType)
    {
        case kLinkEthernet:
        case kLinkRawA:
        case kLinkRawB:
        case kLinkLinuxSll:
        case kLinkLinuxSll2:
        case kLinkIpv4:
        case kLinkIpv6:
            break;
        default:
            throw fileError(
                path, 0,
                "unsupported link type " + linkTypeName() +
                    " (expected Ethernet, Linux cooked or raw IP)");
    }
}

PcapReader::~PcapReader() = default;

std::string PcapReader::linkTypeName() const
{
    const char* name = pcap_datalink_val_to_name(impl_->linkType);
    return name ? name : std::to_string(impl_->linkType);
}

uint64_t PcapReader::position() const
{
    FILE* f = pcap_file(impl_->handle);
    const long pos = f ? std::ftell(f) : -1;
    return pos < 0 ? 0 : uint64_t(pos);
}

bool extractUdpDatagram(
    int linkType, const uint8_t* packet, size_t caplen, uint16_t udpPort, PcapUdpDatagram& out,
    PcapReader::Stats& stats)
{
    const uint8_t* p = packet;
    size_t len = caplen;

    // Link layer → the network protocol and where it starts.
    uint16_t ethertype = 0;
    switch (linkType)
    {
        case kLinkEthernet:
            if (len < 14) break;
            ethertype = readBE16(p + 12);
            p += 14, len -= 14;
            while ((ethertype == kEtherVlan || ethertype == kEtherQinQ) && len >= 4)
            {
                ethertype = readBE16(p + 2);
                p += 4, len -= 4;
            }
            break;
        case kLinkLinuxSll:
            if (len < 16) break;
            ethertype = readBE16(p + 14);
            p += 16, len -= 16;
            break;
        case kLinkLinuxSll2:
            if (len < 20) break;
            ethertype = readBE16(p);
            p += 20, len -= 20;
            break;
        default:  // raw IP: the version nibble says which
            if (len >= 1) ethertype = (p[0] >> 4) == 6 ? kEtherIpv6 : kEtherIpv4;
            break;
    }

    // Network layer → UDP header.
    char address[INET6_ADDRSTRLEN] = {0};
    if (ethertype == kEtherIpv4 && len >= 20 && (p[0] >> 4) == 4)
    {
        const size_t ihl = size_t(p[0] & 0x0F) * 4;
        const bool fragment = (readBE16(p + 6) & 0x3FFF) != 0;
        if (ihl < 20 || len < ihl)
        {
            ++stats.skippedTruncated;
            return false;
        }
        if (p[9] != kProtoUdp || fragment)
        {
            ++stats.skippedNotUdp;
            return false;
        }
        inet_ntop(AF_INET, p + 12, address, sizeof(address));
        p += ihl, len -= ihl;
    }
    else if (ethertype == kEtherIpv6 && len >= 40 && (p[0] >> 4) == 6)
    {
        if (p[6] != kProtoUdp)
        {
            ++stats.skippedNotUdp;
            return false;
        }
        inet_ntop(AF_INET6, p + 8, address, sizeof(address));
        p += 40, len -= 40;
    }
    else
    {
        ++stats.skippedNotIp;
        return false;
    }
    if (len < 8)
    {
        ++stats.skippedTruncated;
        return false;
    }
    const uint16_t udpLength = readBE16(p + 4);
    if (udpLength < 8 || udpLength > len)
    {
        ++stats.skippedTruncated;
        return false;
    }
    out.sourcePort = readBE16(p);
    out.destinationPort = readBE16(p + 2);
    if (udpPort && out.destinationPort != udpPort)
    {
        ++stats.skippedOtherPort;
        return false;
    }
    out.payload = p + 8;
    out.payloadLength = udpLength - 8u;
    out.sourceAddress = address;
    out.sourceAddress = address;
    return true;
}

bool PcapReader::next(PcapUdpDatagram& out)
{
    for (;;)
    {
        const uint64_t recordOffset = position();
        pcap_pkthdr* hdr = nullptr;
        const u_char* pkt = nullptr;
        const int rc = pcap_next_ex(impl_->handle, &hdr, &pkt);
        if (rc == PCAP_ERROR_BREAK) return false;  // end of file
        if (rc != 1 &&
            std::string(pcap_geterr(impl_->handle)).find("truncated") != std::string::npos &&
            fileSize() > recordOffset)
        {
            // libpcap: "truncated dump file; tried to read N ... only got M" — the last record.
            stats_.truncatedTail = true;
            stats_.truncatedTailOffset = recordOffset;
            return false;
        }
        if (rc != 1)
            throw fileError(
                path_, recordOffset,
                std::string("corrupt or truncated record: ") + pcap_geterr(impl_->handle));
        ++stats_.packets;
        if (!extractUdpDatagram(impl_->linkType, pkt, hdr->caplen, udpPort_, out, stats_)) continue;
        out.fileOffset = recordOffset;
        // Opened with nanosecond precision: tv_usec holds nanoseconds.
        out.timestamp = mrpt::Clock::fromDouble(double(hdr->ts.tv_sec)) +
                        std::chrono::duration_cast<mrpt::Clock::duration>(
                            std::chrono::nanoseconds(hdr->ts.tv_usec));
        ++stats_.udp;
        return true;
    }
}

struct PcapWriter::Impl
{
    pcap_t* dead = nullptr;
    pcap_dumper_t* dumper = nullptr;
    std::vector<uint8_t> frame;
    ~Impl()
    {
        if (dumper) pcap_dump_close(dumper);
        if (dead) pcap_close(dead);
    }
};

PcapWriter::PcapWriter(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path)
{
    impl_->dead = pcap_open_dead(kLinkEthernet, 65535);
    impl_->dumper = impl_->dead ? pcap_dump_open(impl_->dead, path.c_str()) : nullptr;
    if (!impl_->dumper)
        throw std::runtime_error(
            "cannot create pcap file '" + path +
            "': " + (impl_->dead ? pcap_geterr(impl_->dead) : "libpcap failed"));
}

PcapWriter::~PcapWriter()
{
    close();
}

void PcapWriter::close()
{
    if (!impl_ || !impl_->dumper) return;
    pcap_dump_close(impl_->dumper);
    impl_->dumper = nullptr;
}

void PcapWriter::writeUdp(
    const uint8_t* payload, size_t len, mrpt::Clock::time_point t, uint32_t sourceIpv4,
    uint32_t destinationIpv4, uint16_t port)
{
    ASSERTMSG_(impl_->dumper, "PcapWriter: write after close()");
    ASSERT_LE_(len, 65507u);
    auto& f = impl_->frame;
    f.assign(14 + 20 + 8 + len, 0);
    uint8_t* p = f.data();
    std::memset(p, 0xFF, 6);  // broadcast destination, as the router's bridge emits it
    const uint8_t nexmonSource[6] = {'N', 'E', 'X', 'M', 'O', 'N'};
    std::memcpy(p + 6, nexmonSource, 6);
    p[12] = 0x08, p[13] = 0x00;
    uint8_t* ip = p + 14;
    const uint16_t ipLength = uint16_t(20 + 8 + len);
    ip[0] = 0x45;
    ip[2] = uint8_t(ipLength >> 8), ip[3] = uint8_t(ipLength);
    ip[8] = 64;  // TTL
    ip[9] = kProtoUdp;
    const uint32_t src = htonl(sourceIpv4), dst = htonl(destinationIpv4);
    std::memcpy(ip + 12, &src, 4);
    std::memcpy(ip + 16, &dst, 4);
    uint32_t sum = 0;
    for (int i = 0; i < 20; i += 2) sum += uint32_t(ip[i] << 8 | ip[i + 1]);
    while (sum >> 16) sum = (sum & 0xFFFF) + (sum >> 16);
    const uint16_t checksum = uint16_t(~sum);
    ip[10] = uint8_t(checksum >> 8), ip[11] = uint8_t(checksum);
    uint8_t* udp = ip + 20;
    udp[0] = udp[2] = uint8_t(port >> 8);
    udp[1] = udp[3] = uint8_t(port);
    const uint16_t udpLength = uint16_t(8 + len);
    udp[4] = uint8_t(udpLength >> 8), udp[5] = uint8_t(udpLength);
    std::memcpy(udp + 8, payload, len);  // UDP checksum 0, as Nexmon sends it

    const double secs = mrpt::Clock::toDouble(t);
    pcap_pkthdr hdr{};
    hdr.ts.tv_sec = time_t(secs);
    hdr.ts.tv_usec = suseconds_t((secs - double(hdr.ts.tv_sec)) * 1e6);
    hdr.caplen = hdr.len = bpf_u_int32(f.size());
    pcap_dump(reinterpret_cast<u_char*>(impl_->dumper), &hdr, f.data());
    ++packets_;
}

}  // namespace mrpt_wifi
