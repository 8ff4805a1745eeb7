/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <cctype>

namespace mrpt_wifi
{
namespace
{
/** Nexmon CSI UDP datagrams in a pcap / pcapng capture, any of the four chips. */
class NexmonDecoder : public CsiDecoder
{
public:
    std::string name() const override { return "nexmon"; }
    std::string description() const override
    {
        return "Nexmon CSI UDP datagrams in a pcap/pcapng capture: BCM4366c0 (RT-AC86U), "
               "BCM43455c0 (Raspberry Pi), BCM4358, BCM4339; 20/40/80 MHz";
    }
    int probe(const uint8_t* head, size_t len) const override
    {
        if (len < 4) return 0;
        const uint32_t magic = uint32_t(head[0]) | uint32_t(head[1]) << 8 |
                               uint32_t(head[2]) << 16 | uint32_t(head[3]) << 24;
        switch (magic)
        {
            case 0xA1B2C3D4:
            case 0xD4C3B2A1:
            case 0xA1B23C4D:
            case 0x4D3CB2A1:
            case 0x0A0D0D0A:
                return 100;
            default:
                return 0;
        }
    }
    void decodeFile(
        const std::string& path, const CsiDecodeOptions& options, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const override
    {
        CsiFileReadOptions o;
        o.assembler = options.assembler;
        o.udpPort = options.udpPort;
        o.strict = options.strict;
        CsiFileReadSummary s;
        const auto fill = [&]
        {
            summary.records = s.pcap.udp;
            summary.frames = s.frames;
            summary.details = s.asString();
            // CsiDecodeSummary prints the frame count itself.
            if (const auto cut = summary.details.rfind("\nCSI frames:"); cut != std::string::npos)
                summary.details.erase(cut);
            // Datagrams the assembler rejected: skipped and counted, by reason.
            summary.rejected.clear();
            for (size_t r = 0; r < s.assembler.rejected.size(); ++r)
                if (const uint64_t n = s.assembler.rejected[r])
                {
                    CsiRejectedRecords rr;
                    rr.reason = std::string("Nexmon datagram rejected: ") +
                                nexmon::toString(nexmon::RejectReason(r));
                    rr.count = n;
                    rr.firstOffset = s.firstRejectedOffset[r];
                    rr.firstWhere = "byte " + std::to_string(rr.firstOffset);
                    summary.rejected.push_back(rr);
                }
            if (s.pcap.truncatedTail)
                summary.noteOnce(
                    "the last record (byte " + std::to_string(s.pcap.truncatedTailOffset) +
                    ") is truncated (a capture that was stopped?); ignored");
        };
        try
        {
            readCsiFrames(path, o, onFrame, onProgress, &s);
        }
        catch (const std::exception& e)
        {
            fill();
            throw std::runtime_error(std::string(e.what()) + " (nexmon format)");
        }
        fill();
    }
};

/** MRPT rawlogs (plain or gzip) holding CObservationWiFiCSI, written by any decoder. */
class RawlogDecoder : public CsiDecoder
{
public:
    std::string name() const override { return "rawlog"; }
    std::string description() const override
    {
        return "MRPT rawlog (plain or gzip) of CObservationWiFiCSI from any source";
    }
    int probe(const uint8_t* head, size_t len) const override
    {
        if (len >= 2 && head[0] == 0x1F && head[1] == 0x8B) return 60;  // gzip
        // A plain MRPT archive starts with an object: 0x80 | class-name length, then the name.
        if (len >= 8 && (head[0] & 0x80) && (head[0] & 0x7F) > 0 &&
            size_t(head[0] & 0x7F) + 1 <= len)
        {
            for (size_t i = 1; i <= size_t(head[0] & 0x7F); ++i)
                if (!std::isalnum(head[i]) && head[i] != '_' && head[i] != ':') return 0;
            return 50;
        }
        return 0;
    }
    void decodeFile(
        const std::string& path, const CsiDecodeOptions&, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const override
    {
        CsiFileReadSummary s;
        const auto fill = [&]
        {
            summary.records = s.rawlogObjects;
            summary.frames = s.frames;
        };
        try
        {
            readCsiFrames(path, {}, onFrame, onProgress, &s);
        }
        catch (...)
        {
            fill();
            throw;
        }
        fill();
    }
};
}  // namespace
}  // namespace mrpt_wifi

using mrpt_wifi::NexmonDecoder;
using mrpt_wifi::RawlogDecoder;
MRPT_WIFI_REGISTER_CSI_DECODER(NexmonDecoder)
MRPT_WIFI_REGISTER_CSI_DECODER(RawlogDecoder)
