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
#include <vector>

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
    /** Receive cores accepted (bit i = core i); others are rejected. Which of them a frame is
     * expected to have is learnt from the transmitter's frames (UbiLocate headers say it). */
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
    /** True duplicates: a (sequence control, core, stream) again with identical CSI words. */
    uint64_t duplicates = 0;
    /** 802.11 retries: a (sequence control, core, stream) again with other CSI — another
     *  reception of the same frame, kept as a frame of its own. */
    uint64_t retries = 0;
    /** Frames started behind a newer frame of their transmitter (reordered on the way); kept. */
    uint64_t lateFrames = 0;
    /** Datagrams of a frame that had already been emitted without them; dropped. */
    uint64_t lateDatagrams = 0;
    uint64_t framesComplete = 0;
    uint64_t framesIncomplete = 0;  //!< emitted by timeout / next frame / flush with pairs missing
    uint64_t missingPairs = 0;      //!< summed over incomplete frames
    uint8_t coresSeen = 0;          //!< receive cores any frame arrived on (bit i = core i)

    uint64_t rejectedTotal() const;
    uint64_t frames() const { return framesComplete + framesIncomplete; }
    /** One line per non-zero counter, for logs and CLI summaries. */
    std::string asString() const;
};

/** Groups the datagrams of one overheard frame (same transmitter, sequence control and
 * chanspec; one datagram per core × stream) into a CObservationWiFiCSI.
 *
 * A frame is emitted as soon as it is complete, when a newer frame of its transmitter starts,
 * after `frameTimeout_s`, or by flushAll(). "Complete" means every core the transmitter's
 * frames arrive on × every stream it sends. Neither is said by the current firmware (the
 * router reports the cores `makecsiparams -C` asked for, e.g. 0, 1, 3 with core mask 0xb), so
 * both are learnt from the transmitter's frames, the first of which therefore waits for the
 * next frame or the timeout. Frames hold only the cores that arrived or were expected
 * (CObservationWiFiCSI::rxCores says which when it isn't 0..n−1).
 *
 * What real captures do is kept, not lost: a datagram repeating a (sequence control, core,
 * stream) with other CSI words is an 802.11 retry — another reception — and starts a frame of
 * its own (identical words are a duplicate and dropped); a frame whose datagrams arrive after a
 * newer frame's is assembled and emitted too. Only a datagram of a frame already emitted
 * without it is dropped ("late"). Malformed datagrams are counted, never thrown. */
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
    /** What identifies the datagrams of one reception, and a hash of each pair's CSI words so
     *  a repeat can be told apart from a retry. */
    struct FrameKey
    {
        uint16_t sequenceControl = 0;
        uint16_t chanspecRaw = 0;
        uint16_t firmwareCounter = 0;
        NexmonHeaderVariant variant = NexmonHeaderVariant::Nexmon;
        bool operator==(const FrameKey& o) const
        {
            return sequenceControl == o.sequenceControl && chanspecRaw == o.chanspecRaw &&
                   firmwareCounter == o.firmwareCounter && variant == o.variant;
        }
    };
    struct PairHashes
    {
        uint64_t present = 0;  //!< bit stream·8 + core
        std::array<uint64_t, 64> hash{};
        /** 0: pair absent; 1: present with the same words; 2: present with other words. */
        int compare(uint8_t bit, uint64_t h) const
        {
            return !((present >> bit) & 1u) ? 0 : hash[bit] == h ? 1 : 2;
        }
    };
    struct OpenFrame
    {
        FrameKey key;
        CObservationWiFiCSI::Ptr obs;  //!< rows = cores 0..n−1 while assembling
        uint8_t headerCores = 0;       //!< cores the header says the frame has (0 = not said)
        mrpt::Clock::time_point firstArrival;
        PairHashes pairs;
    };
    struct Transmitter
    {
        std::vector<OpenFrame> open;  //!< oldest first
        /** Frames emitted lately: a ring, the next one goes to recentNext. */
        std::vector<FrameKey> recentKeys;
        std::vector<PairHashes> recentPairs;
        size_t recentNext = 0;
        uint8_t streamsSeen = 0;  //!< learnt: every stream this transmitter sent
        uint8_t coresSeen = 0;    //!< learnt: every core its frames arrived on
        /** Whether streamsSeen / coresSeen can say when a frame is complete: the header says
         * (UbiLocate), or a whole frame went by. Until then a frame waits for the next one or
         * the timeout, so a stream-major datagram order can't cut the first frame short. */
        bool shapeKnown = false;
        uint16_t newestSequence = 0;  //!< of the newest frame started (late ones are behind)
        bool hasNewest = false;
        mrpt::Clock::time_point lastActivity;
    };

    OpenFrame& startFrame(
        Transmitter& t, const FrameKey& key, const nexmon::DatagramHeader& h,
        mrpt::Clock::time_point arrival, const std::string& source);
    void emit(Transmitter& t, size_t openIndex);
    uint8_t expectedCores(const Transmitter& t, const OpenFrame& f) const;
    bool frameComplete(const Transmitter& t, const OpenFrame& f) const;
    void evictStalest();

    CsiFrameAssemblerOptions options_;
    FrameCallback onFrame_;
    CsiFrameAssemblerStats stats_;
    std::unordered_map<MacAddress, Transmitter> transmitters_;
};

}  // namespace mrpt_wifi
