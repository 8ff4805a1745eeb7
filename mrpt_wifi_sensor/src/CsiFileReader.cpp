/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/RawlogReader.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <array>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
void readCapture(
    const std::string& path, const CsiFileReadOptions& options,
    const std::function<void(CObservationWiFiCSI::Ptr&&)>& onFrame,
    const std::function<void(double)>& onProgress, CsiFileReadSummary& summary)
{
    PcapReader reader(path, options.udpPort);
    // A frame reordered on the way (late) is emitted after a newer one: hold frames by
    // timestamp until no open frame can be older, so they come out in time order.
    std::multimap<mrpt::Clock::time_point, CObservationWiFiCSI::Ptr> held;
    const auto release = [&](mrpt::Clock::time_point upTo)
    {
        while (!held.empty() && held.begin()->first <= upTo)
        {
            ++summary.frames;
            onFrame(std::move(held.begin()->second));
            held.erase(held.begin());
        }
    };
    CsiFrameAssembler assembler(
        options.assembler,
        [&](CObservationWiFiCSI::Ptr&& obs) { held.emplace(obs->timestamp, std::move(obs)); });
    const auto timeout = std::chrono::duration_cast<mrpt::Clock::duration>(
        std::chrono::duration<double>(options.assembler.frameTimeout_s));
    ProgressThrottle progress(onProgress);
    const auto finish = [&]
    {
        assembler.flushAll();
        release(mrpt::Clock::time_point::max());
        summary.pcap = reader.stats();
        summary.assembler = assembler.stats();
    };
    try
    {
        PcapUdpDatagram d;
        while (reader.next(d))
        {
            // Capture time drives the timeout, so a replay assembles exactly as live capture.
            assembler.flushExpired(d.timestamp);
            release(d.timestamp - timeout);  // every open frame is younger
            nexmon::RejectReason why{};
            if (!assembler.push(d.payload, d.payloadLength, d.timestamp, d.sourceAddress, &why))
            {
                if (options.strict)
                    throw std::runtime_error(
                        "'" + path + "' at byte " + std::to_string(d.fileOffset) +
                        ": datagram rejected (" + nexmon::toString(why) + ")");
                if (assembler.stats().rejected[size_t(why)] == 1)
                    summary.firstRejectedOffset[size_t(why)] = d.fileOffset;
            }
            progress.update(reader.position(), reader.fileSize());
        }
    }
    catch (...)
    {
        finish();
        throw;
    }
    finish();
    progress.update(1, 1);
}

void readRawlog(
    const std::string& path, const std::function<void(CObservationWiFiCSI::Ptr&&)>& onFrame,
    const std::function<void(double)>& onProgress, CsiFileReadSummary& summary)
{
    summary.rawlogObjects = forEachRawlogObservation(
        path,
        [&](const mrpt::obs::CObservation::Ptr& o)
        {
            if (auto csi = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
            {
                ++summary.frames;
                onFrame(std::move(csi));
            }
        },
        onProgress);
}
}  // namespace

bool isCaptureMagic(const uint8_t* m)
{
    const uint32_t magic =
        uint32_t(m[0]) | uint32_t(m[1]) << 8 | uint32_t(m[2]) << 16 | uint32_t(m[3]) << 24;
    switch (magic)
    {
        case 0xA1B2C3D4:  // pcap, µs
        case 0xD4C3B2A1:  // pcap, µs, other byte order
        case 0xA1B23C4D:  // pcap, ns
        case 0x4D3CB2A1:
        case 0x0A0D0D0A:  // pcapng section header block
            return true;
        default:
            return false;
    }
}

CsiFileKind detectCsiFileKind(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open '" + path + "'");
    std::array<uint8_t, 4> m{};
    in.read(reinterpret_cast<char*>(m.data()), 4);
    if (in.gcount() < 4)
        throw std::runtime_error("'" + path + "' is empty or shorter than 4 bytes");
    return isCaptureMagic(m.data()) ? CsiFileKind::Pcap : CsiFileKind::Rawlog;
}

std::string CsiFileReadSummary::asString() const
{
    std::ostringstream o;
    if (kind == CsiFileKind::Pcap)
    {
        o << "capture: " << pcap.packets << " packets, " << pcap.udp << " CSI-port datagrams";
        const uint64_t skipped =
            pcap.skippedNotIp + pcap.skippedNotUdp + pcap.skippedOtherPort + pcap.skippedTruncated;
        if (skipped)
            o << ", skipped " << skipped << " (not IP " << pcap.skippedNotIp << ", not UDP "
              << pcap.skippedNotUdp << ", other port " << pcap.skippedOtherPort << ", truncated "
              << pcap.skippedTruncated << ")";
        o << "\nassembler: " << assembler.asString();
    }
    else
        o << "rawlog: " << rawlogObjects << " objects";
    o << "\nCSI frames: " << frames;
    return o.str();
}

void readCsiFrames(
    const std::string& path, const CsiFileReadOptions& options,
    const std::function<void(CObservationWiFiCSI::Ptr&&)>& onFrame,
    const std::function<void(double)>& onProgress, CsiFileReadSummary* summaryOut)
{
    CsiFileReadSummary local;
    CsiFileReadSummary& summary = summaryOut ? *summaryOut : local;
    summary = CsiFileReadSummary{};
    summary.kind = detectCsiFileKind(path);
    if (summary.kind == CsiFileKind::Pcap)
        readCapture(path, options, onFrame, onProgress, summary);
    else
        readRawlog(path, onFrame, onProgress, summary);
}

}  // namespace mrpt_wifi
