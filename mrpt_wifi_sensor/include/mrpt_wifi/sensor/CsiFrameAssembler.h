/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <unordered_map>

namespace mrpt_wifi
{
/** What to do with the bins the firmware overwrites with PHY status (DESIGN.md §4). */
enum class OverwrittenBinPolicy : uint8_t
{
    Keep = 0,  //!< leave the words as they came
    Repair,    //!< interpolate data subcarriers from their neighbours; zero and mask the rest
    Mask       //!< zero them and list them in CObservationWiFiCSI::maskedBins
};
const char* toString(OverwrittenBinPolicy p);
/** Parses "keep|repair|mask"; throws std::invalid_argument otherwise. */
OverwrittenBinPolicy overwrittenBinPolicyFromString(const std::string& s);

/** Applies a policy to the overwritten bins of every present pair of a frame. */
void applyOverwrittenBinPolicy(CObservationWiFiCSI& obs, OverwrittenBinPolicy policy);

struct CsiFrameAssemblerOptions
{
    nexmon::FormatHint format = nexmon::FormatHint::Auto;
    /** Receive cores a frame is expected to have (bit i = core i). UbiLocate headers say it
     * themselves; the current firmware reports only what makecsiparams -C asked for. */
    uint8_t coreMask = 0x0F;
    /** Spatial streams accepted (bit i = stream i). A frame is complete once it has every
     * core × every stream this transmitter has been seen sending. */
    uint8_t streamMask = 0x0F;
    /** A frame still incomplete this long after its first datagram is emitted as it is. */
    double frameTimeout_s = 0.1;
    OverwrittenBinPolicy overwrittenBins = OverwrittenBinPolicy::Repair;
    /** Transmitters tracked at once; the stalest pending frame is emitted to make room. */
    size_t maxPendingTransmitters = 256;
    std::string sensorLabel = "WIFI_CSI";
    mrpt::poses::CPose3D sensorPose;
};

/** Counters of everything the assembler saw. */
struct CsiFrameAssemblerStats
{
    uint64_t datagrams = 0;  //!< pushed in
    uint64_t accepted = 0;   //!< parsed and placed in a frame
    std::array<uint64_t, size_t(nexmon::RejectReason::Count)> rejected{};
    uint64_t duplicates = 0;  //!< a (core, stream) already present in its frame
    /** Reordered: arrived after a later frame of their transmitter had started, so their
     * frame was already emitted; dropped. */
    uint64_t lateDatagrams = 0;
    uint64_t framesComplete = 0;
    uint64_t framesIncomplete = 0;  //!< emitted by timeout / next frame / flush with pairs missing
    uint64_t missingPairs = 0;      //!< summed over incomplete frames

    uint64_t rejectedTotal() const;
    uint64_t frames() const { return framesComplete + framesIncomplete; }
    /** One line per non-zero counter, for logs and CLI summaries. */
    std::string asString() const;
};

/** Groups the datagrams of one overheard frame (same transmitter, sequence control and
 * chanspec; one datagram per core × stream) into a CObservationWiFiCSI.
 *
 * A frame is emitted as soon as it is complete, when the next frame of its transmitter starts,
 * after `frameTimeout_s`, or by flushAll(). "Complete" means every expected core × every stream
 * the transmitter sends; the current firmware doesn't say how many streams that is, so it is
 * learnt from the transmitter's first frame (which therefore waits for the next frame or the
 * timeout). A transmitter that later sends fewer streams yields frames emitted as incomplete,
 * one frame late. Malformed datagrams are counted, never thrown. */
class CsiFrameAssembler
{
public:
    using FrameCallback = std::function<void(CObservationWiFiCSI::Ptr&&)>;

    CsiFrameAssembler(const CsiFrameAssemblerOptions& options, FrameCallback onFrame);

    /** Feeds one UDP payload that arrived at `arrival` from `source` (e.g. the router's IP).
     * Returns false if it was rejected (counted in stats(); the reason also in `why`). */
    bool push(
        const uint8_t* data, size_t len, mrpt::Clock::time_point arrival,
        const std::string& source = {}, nexmon::RejectReason* why = nullptr);
    /** Emits frames whose first datagram is older than the timeout at time `now`. */
    void flushExpired(mrpt::Clock::time_point now);
    /** Emits every pending frame (end of input). */
    void flushAll();

    const CsiFrameAssemblerStats& stats() const { return stats_; }
    const CsiFrameAssemblerOptions& options() const { return options_; }
    size_t pendingFrames() const;

private:
    struct Pending
    {
        CObservationWiFiCSI::Ptr obs;  //!< null when no frame is pending
        uint16_t sequenceControl = 0;
        uint16_t chanspecRaw = 0;
        uint16_t firmwareCounter = 0;
        uint8_t expectedCores = 0;
        mrpt::Clock::time_point firstArrival;
        uint16_t lastEmittedSequence = 0;
        uint64_t lastEmittedMask = 0;  //!< pairs of the last emitted frame
        bool hasEmitted = false;
        uint8_t streamsSeen = 0;  //!< learnt: every stream this transmitter sent
        /** Whether streamsSeen can be trusted to say when a frame is complete: the header says
         * (UbiLocate), or a whole frame went by. Until then a frame waits for the next one or
         * the timeout, so a stream-major datagram order can't cut the first frame short. */
        bool streamsKnown = false;
    };

    void startFrame(
        Pending& p, const nexmon::DatagramHeader& h, mrpt::Clock::time_point arrival,
        const std::string& source);
    void emit(Pending& p);
    bool frameComplete(const Pending& p) const;
    void evictStalest();

    CsiFrameAssemblerOptions options_;
    FrameCallback onFrame_;
    CsiFrameAssemblerStats stats_;
    std::unordered_map<MacAddress, Pending> transmitters_;
};

}  // namespace mrpt_wifi
