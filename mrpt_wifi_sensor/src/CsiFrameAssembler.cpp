/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace mrpt_wifi
{
namespace
{
/** How far behind the newest sequence number a datagram may be and still count as "late"
 * rather than a transmitter that restarted its sequence. */
constexpr uint16_t kLateWindow = 64;
constexpr uint16_t kSequenceModulo = 4096;
/** Receptions of one transmitter assembled at once (a frame, its retry, a late one). */
constexpr size_t kMaxOpenFrames = 4;
/** Emitted frames remembered per transmitter to tell a late repeat from a retry. */
constexpr size_t kRecentFrames = 16;

unsigned highestBitPlusOne(unsigned mask)
{
    return mask ? 32u - unsigned(__builtin_clz(mask)) : 0u;
}

/** A fingerprint of a pair's CSI words, to tell a repeated datagram (same words) from another
 *  reception of the frame (an 802.11 retry: noise alone changes every word). 32 words spread
 *  over the band, FNV-1a a word at a time, keep assembly at its speed (bench_nexmon_decode);
 *  hashing every byte of an 80 MHz pair cost a sixth of it. */
uint64_t wordsFingerprint(const uint8_t* words, unsigned nfft)
{
    const unsigned step = std::max(1u, nfft / 32);
    uint64_t h = 1469598103934665603ull;
    for (unsigned i = 0; i < nfft; i += step)
    {
        uint32_t w;
        std::memcpy(&w, words + 4 * i, 4);
        h = (h ^ w) * 1099511628211ull;  // a word at a time: the words differ, not their bytes
    }
    return h;
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
      << framesIncomplete << ", missing pairs " << missingPairs << ")";
    if (coresSeen)
    {
        o << " on receive cores ";
        for (unsigned c = 0, n = 0; c < 8; ++c)
            if ((coresSeen >> c) & 1u) o << (n++ ? ", " : "") << c;
    }
    o << "; retries kept " << retries << ", late frames kept " << lateFrames
      << ", duplicates dropped " << duplicates << ", late datagrams dropped " << lateDatagrams;
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
    size_t n = 0;
    for (const auto& kv : transmitters_) n += kv.second.open.size();
    return n;
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
        it = transmitters_.emplace(h.transmitter, Transmitter{}).first;
    }
    Transmitter& t = it->second;
    t.lastActivity = arrival;

    const FrameKey key{h.sequenceControl, h.chanspec.raw, h.firmwareCounter, h.variant};
    const auto bit = uint8_t(h.stream * CObservationWiFiCSI::kMaxChains + h.core);
    const uint64_t hash = wordsFingerprint(data + nexmon::csiOffset(), h.nfft());

    // The newest open reception of this frame, if any.
    OpenFrame* frame = nullptr;
    for (auto f = t.open.rbegin(); f != t.open.rend() && !frame; ++f)
        if (f->key == key) frame = &*f;
    bool retry = false;
    if (frame)
    {
        const int seen = frame->pairs.compare(bit, hash);
        if (seen == 1)
        {
            ++stats_.duplicates;
            return true;
        }
        retry = seen == 2;
    }
    else
    {
        // A frame emitted lately: its pair again is a duplicate or a retry; a pair it lacked
        // comes too late to join it.
        for (size_t age = 1; age <= t.recentKeys.size(); ++age)
        {
            // Newest first.
            const size_t r = (t.recentNext + t.recentKeys.size() - age) % t.recentKeys.size();
            if (!(t.recentKeys[r] == key)) continue;
            const int seen = t.recentPairs[r].compare(bit, hash);
            if (seen == 1)
            {
                ++stats_.duplicates;
                return true;
            }
            if (seen == 0)
            {
                ++stats_.lateDatagrams;
                t.streamsSeen |= uint8_t(1u << h.stream);  // still teaches what the AP sends
                t.coresSeen |= uint8_t(1u << h.core);
                return true;
            }
            retry = true;
            break;
        }
    }
    // Firmware other than the 4366c0 may give every frame the same sequence number (the Pi's
    // BCM43455c0): a new frame there, not a retry.
    if (retry && h.chip == nexmon::Chip::BCM4366c0) ++stats_.retries;
    if (!frame || retry)
    {
        frame = &startFrame(t, key, h, arrival, source);
        if (retry) frame->obs->fragmentNumber = h.fragmentNumber();
    }

    auto& obs = *frame->obs;
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
    nexmon::decodeWords(h.chip, data + nexmon::csiOffset(), h.nfft(), obs.pair(h.stream, h.core));
    obs.setPresent(h.stream, h.core);
    frame->pairs.present |= uint64_t(1) << bit;
    frame->pairs.hash[bit] = hash;
    t.streamsSeen |= uint8_t(1u << h.stream);
    t.coresSeen |= uint8_t(1u << h.core);
    stats_.coresSeen |= uint8_t(1u << h.core);
    ++stats_.accepted;
    if (frameComplete(t, *frame)) emit(t, size_t(frame - t.open.data()));
    return true;
}

CsiFrameAssembler::OpenFrame& CsiFrameAssembler::startFrame(
    Transmitter& t, const FrameKey& key, const nexmon::DatagramHeader& h,
    mrpt::Clock::time_point arrival, const std::string& source)
{
    // Open frames behind the new one (or the same frame, for a retry) are done. One ahead of
    // it stays open: the new frame is a late one, reordered on the way.
    const auto ahead = [&](uint16_t sequenceNumber)
    {
        const auto d = uint16_t((sequenceNumber - h.sequenceNumber()) & (kSequenceModulo - 1));
        return d > 0 && d < kLateWindow;
    };
    for (size_t i = t.open.size(); i-- > 0;)
        if (!ahead(uint16_t(t.open[i].key.sequenceControl >> 4))) emit(t, i);
    if (t.hasNewest && ahead(t.newestSequence))
        ++stats_.lateFrames;
    else
    {
        t.newestSequence = h.sequenceNumber();
        t.hasNewest = true;
    }
    if (t.open.size() >= kMaxOpenFrames) emit(t, 0);

    if (h.streamMask)
    {
        t.streamsSeen |= uint8_t(h.streamMask & options_.streamMask);
        t.shapeKnown = true;
    }
    OpenFrame f;
    f.key = key;
    f.firstArrival = arrival;
    f.headerCores = uint8_t(h.coreMask & options_.coreMask);
    const auto chipCoreMask = uint8_t((1u << nexmon::chipCores(h.chip)) - 1);
    const uint8_t layoutCores =
        f.headerCores ? f.headerCores : uint8_t(options_.coreMask & chipCoreMask);

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
    obs->resize(
        std::max(1u, highestBitPlusOne(t.streamsSeen | uint8_t(1u << h.stream))),
        highestBitPlusOne(layoutCores), h.nfft());
    f.obs = std::move(obs);
    t.open.push_back(std::move(f));
    return t.open.back();
}

uint8_t CsiFrameAssembler::expectedCores(const Transmitter& t, const OpenFrame& f) const
{
    return f.headerCores ? f.headerCores : uint8_t(t.coresSeen & options_.coreMask);
}

bool CsiFrameAssembler::frameComplete(const Transmitter& t, const OpenFrame& f) const
{
    if (!t.shapeKnown) return false;
    const uint64_t expected = pairMask(expectedCores(t, f), t.streamsSeen);
    return (f.obs->presentMask & expected) == expected;
}

void CsiFrameAssembler::emit(Transmitter& t, size_t openIndex)
{
    OpenFrame f = std::move(t.open[openIndex]);
    t.open.erase(t.open.begin() + std::ptrdiff_t(openIndex));
    t.shapeKnown = true;  // a whole frame went by: its streams and cores are what the AP sends
    const uint8_t expectedMask = expectedCores(t, f);
    const uint64_t expected = pairMask(expectedMask, t.streamsSeen);
    if ((f.obs->presentMask & expected) == expected)
        ++stats_.framesComplete;
    else
    {
        ++stats_.framesIncomplete;
        stats_.missingPairs += uint64_t(__builtin_popcountll(expected & ~f.obs->presentMask));
    }

    // Keep the rows of the cores that arrived or were expected: a router reporting cores
    // 0, 1, 3 gives three rows, not four with one always missing.
    auto& obs = *f.obs;
    uint8_t keep = expectedMask;
    for (unsigned m = 0; m < obs.nTx; ++m)
        keep |= uint8_t((obs.presentMask >> (m * CObservationWiFiCSI::kMaxChains)) & 0xFF);
    keep &= uint8_t((1u << obs.nRx) - 1);
    if (keep != uint8_t((1u << obs.nRx) - 1))
    {
        std::vector<uint8_t> cores;
        for (unsigned c = 0; c < obs.nRx; ++c)
            if ((keep >> c) & 1u) cores.push_back(uint8_t(c));
        const bool contiguous = cores.empty() || cores.back() + 1u == cores.size();
        CObservationWiFiCSI compact;
        compact.chanspec = obs.chanspec;
        compact.resize(obs.nTx, unsigned(cores.size()), obs.nfft());
        for (unsigned m = 0; m < obs.nTx; ++m)
            for (size_t r = 0; r < cores.size(); ++r)
            {
                if (!obs.isPresent(m, cores[r])) continue;
                std::copy_n(obs.pair(m, cores[r]), obs.nfft(), compact.pair(m, unsigned(r)));
                compact.setPresent(m, unsigned(r));
            }
        obs.csi = std::move(compact.csi);
        obs.presentMask = compact.presentMask;
        obs.nRx = uint8_t(cores.size());
        obs.rxCores = contiguous ? std::vector<uint8_t>{} : cores;
    }
    // Only the 4366c0 firmware overwrites CSI words with PHY status (DESIGN.md §4).
    if (obs.source == nexmon::toString(nexmon::Chip::BCM4366c0))
        applyOverwrittenBinPolicy(obs, options_.overwrittenBins);

    if (t.recentKeys.size() < kRecentFrames)
    {
        t.recentKeys.push_back(f.key);
        t.recentPairs.push_back(f.pairs);
    }
    else
    {
        t.recentKeys[t.recentNext] = f.key;
        t.recentPairs[t.recentNext] = f.pairs;
    }
    t.recentNext = (t.recentNext + 1) % kRecentFrames;
    onFrame_(std::move(f.obs));
}

void CsiFrameAssembler::flushExpired(mrpt::Clock::time_point now)
{
    const auto timeout = std::chrono::duration_cast<mrpt::Clock::duration>(
        std::chrono::duration<double>(options_.frameTimeout_s));
    for (auto& kv : transmitters_)
        for (size_t i = kv.second.open.size(); i-- > 0;)
            if (now - kv.second.open[i].firstArrival >= timeout) emit(kv.second, i);
}

void CsiFrameAssembler::flushAll()
{
    for (auto& kv : transmitters_)
        while (!kv.second.open.empty()) emit(kv.second, 0);
}

void CsiFrameAssembler::evictStalest()
{
    // Prefer forgetting a transmitter with nothing pending; otherwise the least recently heard.
    auto victim = transmitters_.end();
    for (auto it = transmitters_.begin(); it != transmitters_.end(); ++it)
    {
        if (it->second.open.empty())
        {
            victim = it;
            break;
        }
        if (victim == transmitters_.end() || it->second.lastActivity < victim->second.lastActivity)
            victim = it;
    }
    if (victim == transmitters_.end()) return;
    while (!victim->second.open.empty()) emit(victim->second, 0);
    transmitters_.erase(victim);
}

}  // namespace mrpt_wifi
