/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>

#include <algorithm>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
/** How far behind the newest sequence number a datagram may be and still count as "late"
 * rather than a transmitter that restarted its sequence. */
constexpr uint16_t kLateWindow = 64;
constexpr uint16_t kSequenceModulo = 4096;

unsigned highestBitPlusOne(unsigned mask)
{
    return mask ? 32u - unsigned(__builtin_clz(mask)) : 0u;
}

/** Bits of CObservationWiFiCSI::presentMask for every core × stream in the two masks. */
uint64_t pairMask(uint8_t cores, uint8_t streams)
{
    uint64_t m = 0;
    for (unsigned tx = 0; tx < 8; ++tx)
        if ((streams >> tx) & 1u) m |= uint64_t(cores) << (tx * CObservationWiFiCSI::kMaxChains);
    return m;
}

/** What Repair does to one overwritten subcarrier: rebuild it from two data neighbours
 * (interpolating, or extrapolating at a band edge), or zero it when it carries no data. */
struct BinRepair
{
    int k = 0;
    bool interpolate = false;
    int k1 = 0, k2 = 0;
};

std::vector<BinRepair> repairPlan(unsigned bandwidthMHz)
{
    const auto overwritten = firmwareOverwrittenSubcarriers(bandwidthMHz);
    const auto& data = dataSubcarriers(bandwidthMHz);
    const auto isOverwritten = [&](int k)
    { return std::find(overwritten.begin(), overwritten.end(), k) != overwritten.end(); };
    std::vector<int> usable;
    for (int k : data)
        if (!isOverwritten(k)) usable.push_back(k);

    std::vector<BinRepair> plan;
    for (int k : overwritten)
    {
        BinRepair r;
        r.k = k;
        r.interpolate = std::binary_search(data.begin(), data.end(), k);
        if (r.interpolate)
        {
            const auto above = std::upper_bound(usable.begin(), usable.end(), k);
            if (above == usable.begin())  // below the lowest: extrapolate from the two lowest
                r.k1 = above[0], r.k2 = above[1];
            else if (above == usable.end())  // above the highest: from the two highest
                r.k1 = above[-2], r.k2 = above[-1];
            else
                r.k1 = above[-1], r.k2 = above[0];
        }
        plan.push_back(r);
    }
    return plan;
}
}  // namespace

const char* toString(OverwrittenBinPolicy p)
{
    switch (p)
    {
        case OverwrittenBinPolicy::Keep:
            return "keep";
        case OverwrittenBinPolicy::Repair:
            return "repair";
        case OverwrittenBinPolicy::Mask:
            return "mask";
    }
    return "?";
}

OverwrittenBinPolicy overwrittenBinPolicyFromString(const std::string& s)
{
    for (auto p :
         {OverwrittenBinPolicy::Keep, OverwrittenBinPolicy::Repair, OverwrittenBinPolicy::Mask})
        if (s == toString(p)) return p;
    throw std::invalid_argument(
        "unknown overwritten-bin policy '" + s + "' (expected keep, repair or mask)");
}

void applyOverwrittenBinPolicy(CObservationWiFiCSI& obs, OverwrittenBinPolicy policy)
{
    if (policy == OverwrittenBinPolicy::Keep) return;
    static const std::vector<BinRepair> plans[3] = {repairPlan(20), repairPlan(40), repairPlan(80)};
    const unsigned bw = obs.chanspec.bandwidthMHz;
    const auto& plan = plans[bw == 20 ? 0 : bw == 40 ? 1 : 2];
    const unsigned n = obs.nfft();

    obs.maskedBins.clear();
    for (const auto& r : plan)
        if (policy == OverwrittenBinPolicy::Mask || !r.interpolate)
            obs.maskedBins.push_back(uint16_t(subcarrierToBin(r.k, n)));

    for (unsigned tx = 0; tx < obs.nTx; ++tx)
        for (unsigned rx = 0; rx < obs.nRx; ++rx)
        {
            if (!obs.isPresent(tx, rx)) continue;
            auto* h = obs.pair(tx, rx);
            for (const auto& r : plan)
            {
                auto& target = h[subcarrierToBin(r.k, n)];
                if (policy == OverwrittenBinPolicy::Repair && r.interpolate)
                {
                    const auto h1 = h[subcarrierToBin(r.k1, n)], h2 = h[subcarrierToBin(r.k2, n)];
                    target = h1 + (h2 - h1) * (float(r.k - r.k1) / float(r.k2 - r.k1));
                }
                else
                    target = {0.0f, 0.0f};
            }
        }
}

uint64_t CsiFrameAssemblerStats::rejectedTotal() const
{
    return std::accumulate(rejected.begin(), rejected.end(), uint64_t(0));
}

std::string CsiFrameAssemblerStats::asString() const
{
    std::ostringstream o;
    o << "datagrams " << datagrams << ", accepted " << accepted << ", rejected " << rejectedTotal();
    for (size_t i = 0; i < rejected.size(); ++i)
        if (rejected[i])
            o << " [" << nexmon::toString(nexmon::RejectReason(i)) << ": " << rejected[i] << "]";
    o << "; frames " << frames() << " (complete " << framesComplete << ", incomplete "
      << framesIncomplete << ", missing pairs " << missingPairs << "); duplicates " << duplicates
      << ", reordered (late) " << lateDatagrams;
    return o.str();
}

CsiFrameAssembler::CsiFrameAssembler(const CsiFrameAssemblerOptions& options, FrameCallback onFrame)
    : options_(options), onFrame_(std::move(onFrame))
{
    if (!onFrame_) throw std::invalid_argument("CsiFrameAssembler: no frame callback");
    if (!(options_.coreMask & 0x0F) || !(options_.streamMask & 0x0F))
        throw std::invalid_argument("CsiFrameAssembler: core and stream masks need a bit in 0x0f");
}

size_t CsiFrameAssembler::pendingFrames() const
{
    return size_t(std::count_if(
        transmitters_.begin(), transmitters_.end(),
        [](const auto& kv) { return bool(kv.second.obs); }));
}

bool CsiFrameAssembler::push(
    const uint8_t* data, size_t len, mrpt::Clock::time_point arrival, const std::string& source,
    nexmon::RejectReason* whyOut)
{
    const auto reject = [&](nexmon::RejectReason why)
    {
        ++stats_.rejected[size_t(why)];
        if (whyOut) *whyOut = why;
        return false;
    };
    ++stats_.datagrams;
    nexmon::DatagramHeader h;
    nexmon::RejectReason why{};
    if (!nexmon::parseHeader(data, len, options_.format, h, why)) return reject(why);
    if (!((options_.coreMask >> h.core) & 1u) || !((options_.streamMask >> h.stream) & 1u))
        return reject(nexmon::RejectReason::BadCoreStream);

    auto it = transmitters_.find(h.transmitter);
    if (it == transmitters_.end())
    {
        if (transmitters_.size() >= options_.maxPendingTransmitters) evictStalest();
        it = transmitters_.emplace(h.transmitter, Pending{}).first;
    }
    Pending& p = it->second;
    const bool sameFrame =
        p.obs && p.sequenceControl == h.sequenceControl && p.chanspecRaw == h.chanspec.raw &&
        p.firmwareCounter == h.firmwareCounter && p.obs->headerVariant == h.variant;
    if (!sameFrame)
    {
        // A datagram a little behind the newest sequence number belongs to a frame that was
        // already emitted: count it, drop it. Anything else starts this transmitter's next frame.
        const bool haveReference = p.obs || p.hasEmitted;
        const uint16_t reference = p.obs ? uint16_t(p.sequenceControl >> 4) : p.lastEmittedSequence;
        const uint16_t behind = uint16_t((reference - h.sequenceNumber()) & (kSequenceModulo - 1));
        // The Raspberry Pi's firmware (BCM43455c0) and other non-4366c0 chips may report the
        // same sequence number for every frame: a pair the last frame already had then starts
        // a new frame rather than being late.
        const uint64_t bit = uint64_t(1) << (h.stream * CObservationWiFiCSI::kMaxChains + h.core);
        const bool repeatsSequence =
            h.chip != nexmon::Chip::BCM4366c0 && !p.obs && behind == 0 && (p.lastEmittedMask & bit);
        if (haveReference && behind < kLateWindow && !(p.obs && behind == 0) && !repeatsSequence)
        {
            ++stats_.lateDatagrams;
            p.streamsSeen |= uint8_t(1u << h.stream);  // still teaches what the AP sends
            return true;
        }
        if (p.obs) emit(p);
        startFrame(p, h, arrival, source);
    }

    auto& obs = *p.obs;
    if (h.core >= obs.nRx)
    {
        // A core the frame's first datagram did not announce (UbiLocate masks disagreeing
        // within one frame): no room for it in this frame's layout. Found by the fuzzer.
        return reject(nexmon::RejectReason::BadCoreStream);
    }
    if (h.stream >= obs.nTx)
    {
        // The transmitter sends more streams than seen so far: grow (tx-major keeps data put).
        obs.nTx = uint8_t(h.stream + 1);
        obs.csi.resize(size_t(obs.nTx) * obs.nRx * obs.nfft());
    }
    if (obs.isPresent(h.stream, h.core))
    {
        if (h.chip == nexmon::Chip::BCM4366c0)
        {
            ++stats_.duplicates;
            return true;
        }
        // Non-4366c0 firmware repeating the sequence number: this pair starts the next frame.
        emit(p);
        startFrame(p, h, arrival, source);
    }
    auto& cur = *p.obs;
    if (h.stream >= cur.nTx)
    {
        cur.nTx = uint8_t(h.stream + 1);
        cur.csi.resize(size_t(cur.nTx) * cur.nRx * cur.nfft());
    }
    nexmon::decodeWords(h.chip, data + nexmon::csiOffset(), h.nfft(), cur.pair(h.stream, h.core));
    cur.setPresent(h.stream, h.core);
    p.streamsSeen |= uint8_t(1u << h.stream);
    ++stats_.accepted;
    if (frameComplete(p)) emit(p);
    return true;
}

void CsiFrameAssembler::startFrame(
    Pending& p, const nexmon::DatagramHeader& h, mrpt::Clock::time_point arrival,
    const std::string& source)
{
    p.sequenceControl = h.sequenceControl;
    p.chanspecRaw = h.chanspec.raw;
    p.firmwareCounter = h.firmwareCounter;
    p.firstArrival = arrival;
    const auto chipCoreMask = uint8_t((1u << nexmon::chipCores(h.chip)) - 1);
    p.expectedCores = h.coreMask ? uint8_t(h.coreMask & options_.coreMask)
                                 : uint8_t(options_.coreMask & chipCoreMask);
    if (h.streamMask)
    {
        p.streamsSeen |= uint8_t(h.streamMask & options_.streamMask);
        p.streamsKnown = true;
    }
    p.streamsSeen |= uint8_t(1u << h.stream);

    auto obs = CObservationWiFiCSI::Create();
    obs->timestamp = arrival;
    obs->sensorLabel = options_.sensorLabel;
    obs->sensorPose = options_.sensorPose;
    obs->transmitter = h.transmitter;
    obs->rssi_dBm = h.rssi_dBm;
    obs->sequenceNumber = h.sequenceNumber();
    obs->fragmentNumber = h.fragmentNumber();
    obs->frameControl = h.frameControl;
    obs->chanspec = h.chanspec;
    obs->chipId = h.chipId;
    obs->source = nexmon::toString(h.chip);
    obs->firmwareCounter = h.firmwareCounter;
    obs->headerVariant = h.variant;
    obs->routerAddress = source;
    obs->resize(highestBitPlusOne(p.streamsSeen), highestBitPlusOne(p.expectedCores), h.nfft());
    p.obs = std::move(obs);
}

bool CsiFrameAssembler::frameComplete(const Pending& p) const
{
    if (!p.streamsKnown) return false;
    const uint64_t expected = pairMask(p.expectedCores, p.streamsSeen);
    return (p.obs->presentMask & expected) == expected;
}

void CsiFrameAssembler::emit(Pending& p)
{
    p.streamsKnown = true;  // a whole frame went by: its streams are what the AP sends
    if (frameComplete(p))
        ++stats_.framesComplete;
    else
    {
        ++stats_.framesIncomplete;
        const uint64_t expected = pairMask(p.expectedCores, p.streamsSeen);
        stats_.missingPairs += uint64_t(__builtin_popcountll(expected & ~p.obs->presentMask));
    }
    // Only the 4366c0 firmware overwrites CSI words with PHY status (DESIGN.md §4).
    if (p.obs->source == nexmon::toString(nexmon::Chip::BCM4366c0))
        applyOverwrittenBinPolicy(*p.obs, options_.overwrittenBins);
    p.lastEmittedSequence = p.obs->sequenceNumber;
    p.lastEmittedMask = p.obs->presentMask;
    p.hasEmitted = true;
    onFrame_(std::move(p.obs));
    p.obs.reset();
}

void CsiFrameAssembler::flushExpired(mrpt::Clock::time_point now)
{
    const auto timeout = std::chrono::duration_cast<mrpt::Clock::duration>(
        std::chrono::duration<double>(options_.frameTimeout_s));
    for (auto& kv : transmitters_)
        if (kv.second.obs && now - kv.second.firstArrival >= timeout) emit(kv.second);
}

void CsiFrameAssembler::flushAll()
{
    for (auto& kv : transmitters_)
        if (kv.second.obs) emit(kv.second);
}

void CsiFrameAssembler::evictStalest()
{
    // Prefer forgetting a transmitter with nothing pending; otherwise emit the oldest frame.
    auto victim = transmitters_.end();
    for (auto it = transmitters_.begin(); it != transmitters_.end(); ++it)
    {
        if (!it->second.obs)
        {
            victim = it;
            break;
        }
        if (victim == transmitters_.end() || it->second.firstArrival < victim->second.firstArrival)
            victim = it;
    }
    if (victim == transmitters_.end()) return;
    if (victim->second.obs) emit(victim->second);
    transmitters_.erase(victim);
}

}  // namespace mrpt_wifi
