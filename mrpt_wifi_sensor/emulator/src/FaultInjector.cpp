/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/emulator/FaultInjector.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>

#include <cmath>
#include <numeric>
#include <stdexcept>

#include "Json.h"

namespace mrpt_wifi::emulator
{
void FaultSettings::validate() const
{
    const std::pair<const char*, double> probabilities[] = {
        {"loss", loss}, {"duplicate", duplicate}, {"reorder", reorder}, {"corrupt", corrupt}};
    for (const auto& [name, p] : probabilities)
        if (!(p >= 0.0 && p <= 1.0))
            throw std::invalid_argument(
                std::string("fault probability '") + name + "' must be in [0, 1], got " +
                detail::jsonNumber(p));
    if (!(silenceRate_Hz >= 0.0) || !std::isfinite(silenceRate_Hz))
        throw std::invalid_argument("silence rate must be >= 0");
    if (!(silenceLength_s >= 0.0) || !std::isfinite(silenceLength_s))
        throw std::invalid_argument("silence length must be >= 0");
}

std::string FaultSettings::toJson() const
{
    detail::JsonObject j;
    j.num("loss", loss)
        .num("duplicate", duplicate)
        .num("reorder", reorder)
        .num("corrupt", corrupt)
        .num("silence_rate_hz", silenceRate_Hz)
        .num("silence_length_s", silenceLength_s);
    return j.json();
}

const char* toString(CorruptionKind k)
{
    switch (k)
    {
        case CorruptionKind::Truncated:
            return "truncated";
        case CorruptionKind::BadMagic:
            return "bad_magic";
        case CorruptionKind::BadChanspec:
            return "bad_chanspec";
        case CorruptionKind::Count:
            break;
    }
    return "?";
}

uint64_t FaultCounters::corruptedTotal() const
{
    return std::accumulate(corrupted.begin(), corrupted.end(), uint64_t(0));
}

std::string FaultCounters::toJson() const
{
    detail::JsonObject c;
    for (size_t k = 0; k < corrupted.size(); ++k) c.uint(toString(CorruptionKind(k)), corrupted[k]);
    detail::JsonObject j;
    j.uint("submitted", submitted)
        .uint("lost", lost)
        .uint("duplicated", duplicated)
        .uint("reordered", reordered)
        .uint("reorder_expired", reorderExpired)
        .uint("corrupted", corruptedTotal())
        .raw("corrupted_by_kind", c.json())
        .uint("corrupted_sent", corruptedSent)
        .uint("silences", silences);
    return j.json();
}

FaultInjector::FaultInjector(uint64_t seed, const FaultSettings& settings)
    : rng_(seed), silenceRng_(seed ^ 0x5111e9ce5111e9ceULL)
{
    setSettings(settings);
}

void FaultInjector::setSettings(const FaultSettings& s)
{
    s.validate();
    settings_ = s;
}

void FaultInjector::corrupt(std::vector<uint8_t>& d, uint64_t kindDraw, uint64_t paramDraw)
{
    const auto kind = CorruptionKind(kindDraw % uint64_t(CorruptionKind::Count));
    ++counters_.corrupted[size_t(kind)];
    switch (kind)
    {
        case CorruptionKind::Truncated:
        {
            // Shorter than the smallest valid datagram of its own bandwidth, so no header
            // variant can accept it.
            size_t limit = d.size();
            if (d.size() >= nexmon::kHeaderBytes)
                if (const auto cs = Chanspec::decode(uint16_t(d[14] | d[15] << 8)))
                    limit = std::min(limit, nexmon::kHeaderBytes + 4 * size_t(cs->nfft()));
            if (limit <= 1)
                d.clear();
            else
                d.resize(1 + size_t(paramDraw % (limit - 1)));
            break;
        }
        case CorruptionKind::BadMagic:
        {
            if (d.empty()) break;
            uint8_t v = uint8_t(paramDraw % 255);
            if (v >= 0x11) ++v;  // anything but 0x11
            d[0] = v;
            break;
        }
        case CorruptionKind::BadChanspec:
        {
            if (d.size() < 16) break;
            static constexpr uint8_t kImpossibleBandwidthCodes[] = {0, 1, 5, 6, 7};
            const uint8_t code = kImpossibleBandwidthCodes[paramDraw % 5];
            d[15] = uint8_t((d[15] & ~0x38) | (code << 3));  // bits 11–13 of the word
            break;
        }
        case CorruptionKind::Count:
            break;
    }
}

void FaultInjector::submit(std::vector<uint8_t> datagram, double time_s, const Sink& sink)
{
    ++counters_.submitted;
    // Always the same number of draws per datagram: decisions stay aligned with the input.
    const double uLoss = uniform(rng_), uCorrupt = uniform(rng_), uDuplicate = uniform(rng_),
                 uReorder = uniform(rng_);
    const uint64_t kindDraw = rng_(), paramDraw = rng_();

    releaseExpired(time_s, sink);
    if (uLoss < settings_.loss)
    {
        ++counters_.lost;
        return;
    }
    const bool corrupted = uCorrupt < settings_.corrupt;
    if (corrupted) corrupt(datagram, kindDraw, paramDraw);
    const unsigned copies = uDuplicate < settings_.duplicate ? 2 : 1;
    counters_.duplicated += copies - 1;

    auto emit = [&](const std::vector<uint8_t>& d, unsigned n, bool bad)
    {
        for (unsigned i = 0; i < n; ++i)
        {
            if (bad) ++counters_.corruptedSent;
            sink(d);
        }
    };
    if (held_)
    {
        // Complete the swap: this one first, then the one that was held back.
        emit(datagram, copies, corrupted);
        emit(held_->datagram, held_->copies, held_->corrupted);
        held_.reset();
        ++counters_.reordered;
    }
    else if (uReorder < settings_.reorder)
        held_ = Held{std::move(datagram), copies, corrupted, time_s};
    else
        emit(datagram, copies, corrupted);
}

void FaultInjector::releaseExpired(double time_s, const Sink& sink)
{
    if (held_ && time_s - held_->time_s > holdLimit_s) flush(sink);
}

void FaultInjector::flush(const Sink& sink)
{
    if (!held_) return;
    Held h = std::move(*held_);
    held_.reset();
    ++counters_.reorderExpired;  // sent alone: nothing overtook it
    for (unsigned i = 0; i < h.copies; ++i)
    {
        if (h.corrupted) ++counters_.corruptedSent;
        sink(h.datagram);
    }
}

bool FaultInjector::silenceStarts(double dt_s)
{
    const double u = uniform(silenceRng_);
    if (settings_.silenceRate_Hz <= 0 || dt_s <= 0) return false;
    const bool starts = u < 1.0 - std::exp(-settings_.silenceRate_Hz * dt_s);
    if (starts) ++counters_.silences;
    return starts;
}

}  // namespace mrpt_wifi::emulator
