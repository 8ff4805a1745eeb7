/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace mrpt_wifi::emulator
{
/** Faults of the router→host link, as probabilities per datagram (0..1). */
struct FaultSettings
{
    double loss = 0;       //!< datagram dropped
    double duplicate = 0;  //!< datagram sent twice
    double reorder = 0;    //!< datagram swapped with the next one sent
    double corrupt = 0;    //!< datagram truncated, magic garbled or chanspec made invalid
    /** Silence episodes (nothing sent) start as a Poisson process of this rate [1/s]... */
    double silenceRate_Hz = 0;
    double silenceLength_s = 0.5;  //!< ...and last this long [s, wall clock]

    /** Throws std::invalid_argument naming the setting if a probability is outside [0, 1] or a
     * rate/length is negative. */
    void validate() const;
    /** The settings as a JSON object. */
    std::string toJson() const;
};

enum class CorruptionKind : uint8_t
{
    Truncated = 0,  //!< shorter than any valid datagram of its bandwidth
    BadMagic,       //!< first byte not 0x11
    BadChanspec,    //!< bandwidth field set to a code the 4366c0 can't use
    Count
};
const char* toString(CorruptionKind k);

struct FaultCounters
{
    uint64_t submitted = 0;  //!< datagrams that entered the injector
    uint64_t lost = 0;
    uint64_t duplicated = 0;  //!< extra copies sent
    uint64_t reordered = 0;   //!< datagrams sent after the one that followed them
    /** Datagrams held for reordering that were sent alone because nothing followed in time. */
    uint64_t reorderExpired = 0;
    std::array<uint64_t, size_t(CorruptionKind::Count)> corrupted{};
    /** Corrupted datagrams put on the wire, duplicates included (what a receiver rejects). */
    uint64_t corruptedSent = 0;
    uint64_t silences = 0;  //!< silence episodes started by silenceRate_Hz

    uint64_t corruptedTotal() const;
    std::string toJson() const;
};

/** Applies FaultSettings to a stream of datagrams, reproducibly: every decision comes from a
 * seeded std::mt19937_64 (fully specified by the C++ standard), with a fixed number of draws
 * per datagram, so the same seed and input give the same output on any platform.
 *
 * Per datagram, in this order: loss (then nothing else happens), corruption, duplication,
 * reordering (the datagram is held and sent right after the next one). A held datagram is
 * sent alone if the next one comes more than holdLimit_s later (stream time). */
class FaultInjector
{
public:
    using Sink = std::function<void(const std::vector<uint8_t>&)>;

    explicit FaultInjector(uint64_t seed = 1, const FaultSettings& settings = {});

    void setSettings(const FaultSettings& s);
    const FaultSettings& settings() const { return settings_; }
    const FaultCounters& counters() const { return counters_; }

    /** One datagram at stream time `time_s`; zero or more datagrams go to `sink`. */
    void submit(std::vector<uint8_t> datagram, double time_s, const Sink& sink);
    /** Sends a held datagram whose hold has expired at `time_s`. */
    void releaseExpired(double time_s, const Sink& sink);
    /** Sends a held datagram now (end of stream, silence). */
    void flush(const Sink& sink);
    bool holding() const { return held_.has_value(); }

    /** Whether a silence episode starts in an interval of `dt_s` seconds (one draw). */
    bool silenceStarts(double dt_s);

    double holdLimit_s = 0.05;

private:
    double uniform(std::mt19937_64& g) { return double(g() >> 11) * 0x1.0p-53; }
    void corrupt(std::vector<uint8_t>& d, uint64_t kindDraw, uint64_t paramDraw);

    FaultSettings settings_;
    FaultCounters counters_;
    std::mt19937_64 rng_, silenceRng_;
    struct Held
    {
        std::vector<uint8_t> datagram;
        unsigned copies = 1;
        bool corrupted = false;
        double time_s = 0;
    };
    std::optional<Held> held_;
};

}  // namespace mrpt_wifi::emulator
