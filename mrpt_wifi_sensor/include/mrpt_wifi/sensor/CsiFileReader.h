/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>
#include <mrpt_wifi/sensor/PcapIO.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>

namespace mrpt_wifi
{
enum class CsiFileKind
{
    Pcap,   //!< pcap or pcapng capture of Nexmon datagrams
    Rawlog  //!< MRPT rawlog (gzip or plain) holding CObservationWiFiCSI
};

/** True if the 4 bytes are a pcap (either byte order, µs or ns) or pcapng magic number. */
bool isCaptureMagic(const uint8_t* first4Bytes);

/** Tells a capture from a rawlog by the first bytes; throws std::runtime_error naming the
 * file if it can't be read or is empty. */
CsiFileKind detectCsiFileKind(const std::string& path);

struct CsiFileReadOptions
{
    CsiFrameAssemblerOptions assembler;          //!< for captures
    uint16_t udpPort = nexmon::kDefaultUdpPort;  //!< for captures (0: any port)
    /** Captures: a datagram the assembler rejects stops the read (std::runtime_error naming
     *  the file, its offset and the reason) instead of being counted. */
    bool strict = false;
};

/** What a read went through. */
struct CsiFileReadSummary
{
    CsiFileKind kind = CsiFileKind::Pcap;
    PcapReader::Stats pcap;            //!< captures only
    CsiFrameAssemblerStats assembler;  //!< captures only
    uint64_t rawlogObjects = 0;  //!< rawlogs only: objects read (observations, frames, actions)
    uint64_t frames = 0;         //!< CSI frames delivered
    /** Captures: per nexmon::RejectReason, the file offset of the first datagram rejected for
     *  it (valid where assembler.rejected[reason] > 0). */
    std::array<uint64_t, size_t(nexmon::RejectReason::Count)> firstRejectedOffset{};
    std::string asString() const;
};

/** Delivers every CSI frame of a capture or rawlog, in file order, to `onFrame`;
 * `onProgress(fraction)` is called now and then. On a corrupt or truncated file it first
 * delivers every frame read before the fault, then throws std::runtime_error naming the file
 * and byte offset; `summary` (if given) is filled either way. */
void readCsiFrames(
    const std::string& path, const CsiFileReadOptions& options,
    const std::function<void(CObservationWiFiCSI::Ptr&&)>& onFrame,
    const std::function<void(double)>& onProgress = {}, CsiFileReadSummary* summary = nullptr);

}  // namespace mrpt_wifi
