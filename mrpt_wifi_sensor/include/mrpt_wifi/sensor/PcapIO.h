/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>

#include <cstdint>
#include <memory>
#include <string>

namespace mrpt_wifi
{
/** One UDP datagram found in a capture. The payload points into the reader's buffer and is
 * valid until the next call to PcapReader::next(). */
struct PcapUdpDatagram
{
    const uint8_t* payload = nullptr;
    size_t payloadLength = 0;
    mrpt::Clock::time_point timestamp;
    std::string sourceAddress;  //!< dotted IPv4 or IPv6 text
    uint16_t sourcePort = 0;
    uint16_t destinationPort = 0;
    uint64_t fileOffset = 0;  //!< where the record starts in the file
};

/** Reads the UDP datagrams of a tcpdump capture with libpcap: pcap or pcapng; Ethernet
 * (with 802.1Q tags), Linux cooked (SLL, SLL2) or raw-IP link types; IPv4 and IPv6. */
class PcapReader
{
public:
    struct Stats
    {
        uint64_t packets = 0;           //!< records read
        uint64_t udp = 0;               //!< UDP datagrams returned
        uint64_t skippedNotIp = 0;      //!< other link/network protocols (ARP, ...)
        uint64_t skippedNotUdp = 0;     //!< IP but not UDP, or IP fragments
        uint64_t skippedOtherPort = 0;  //!< UDP to another port
        uint64_t skippedTruncated = 0;  //!< captured shorter than their headers say (snaplen)
        /** The file ends inside a record (a capture that was stopped): read up to it. */
        bool truncatedTail = false;
        uint64_t truncatedTailOffset = 0;  //!< where that last record starts
    };

    /** Opens `path`; `udpPort` selects datagrams by destination port (0: any).
     * Throws std::runtime_error naming the file if it is missing or not a capture. */
    explicit PcapReader(const std::string& path, uint16_t udpPort = 5500);
    ~PcapReader();
    PcapReader(const PcapReader&) = delete;
    PcapReader& operator=(const PcapReader&) = delete;

    /** Next UDP datagram to the port; false at the end of the file. Throws std::runtime_error
     * naming the file and byte offset when the file is corrupt or truncated. */
    bool next(PcapUdpDatagram& out);

    const Stats& stats() const { return stats_; }
    const std::string& path() const { return path_; }
    uint64_t fileSize() const { return fileSize_; }
    /** Byte offset reached so far (for progress). */
    uint64_t position() const;
    /** libpcap's link-type name, e.g. "EN10MB". */
    std::string linkTypeName() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string path_;
    uint16_t udpPort_;
    uint64_t fileSize_ = 0;
    Stats stats_;
};

/** Finds the UDP datagram to `udpPort` (0: any) in one captured packet of libpcap link type
 * `linkType` (DLT_EN10MB, DLT_LINUX_SLL, DLT_LINUX_SLL2, raw IP): fills payload, length,
 * ports and source address of `out`; false (the reason counted in `stats`) otherwise. Shared
 * by PcapReader and live capture. */
bool extractUdpDatagram(
    int linkType, const uint8_t* packet, size_t caplen, uint16_t udpPort, PcapUdpDatagram& out,
    PcapReader::Stats& stats);

/** Writes Nexmon datagrams as a tcpdump would record them on the router (Ethernet, IPv4,
 * UDP 5500 → 5500 from 10.10.10.10 to 255.255.255.255, checksum 0): classic pcap with
 * microsecond timestamps. This only writes a file; nothing is sent. */
class PcapWriter
{
public:
    /** Throws std::runtime_error naming the file if it can't be created. */
    explicit PcapWriter(const std::string& path);
    ~PcapWriter();
    PcapWriter(const PcapWriter&) = delete;
    PcapWriter& operator=(const PcapWriter&) = delete;

    void writeUdp(
        const uint8_t* payload, size_t len, mrpt::Clock::time_point t,
        uint32_t sourceIpv4 = 0x0A0A0A0A, uint32_t destinationIpv4 = 0xFFFFFFFF,
        uint16_t port = 5500);
    /** Flushes and closes (also done by the destructor). */
    void close();
    uint64_t packetsWritten() const { return packets_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string path_;
    uint64_t packets_ = 0;
};

}  // namespace mrpt_wifi
