/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// Counter-based random numbers: a draw is a pure function of a key and a counter, so frame n
// of transmitter m gets the same noise whatever was simulated before it (channel filters,
// rewinds, reboots). Scenario-level randomness (trajectory, hardware) uses mrpt::random.

#include <cmath>
#include <cstdint>
#include <initializer_list>

namespace mrpt_wifi::sim::detail
{
/** 64-bit avalanche mix (xor-shift / multiply finaliser, as in SplitMix64). */
inline uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/** 32-bit avalanche mix of the same family; cheap enough to vectorise over a frame's bins. */
inline uint32_t mix32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

/** Hash of a list of integers (seed, purpose tag, indices...). */
inline uint64_t hashKey(std::initializer_list<uint64_t> parts)
{
    uint64_t h = 0x6a09e667f3bcc909ULL;
    for (uint64_t p : parts) h = mix64(h ^ (p + 0x9e3779b97f4a7c15ULL));
    return h;
}

/** Seed for an mrpt::random::CRandomGenerator derived from a key. */
inline uint32_t seed32(uint64_t key)
{
    return uint32_t(key ^ (key >> 32));
}

/** Sequential draws from a key. */
class CounterRng
{
public:
    explicit CounterRng(uint64_t key) : key_(key) {}

    uint64_t nextU64() { return mix64(key_ + 0x9e3779b97f4a7c15ULL * ++counter_); }
    /** Uniform in [0, 1). */
    double uniform() { return double(nextU64() >> 11) * (1.0 / 9007199254740992.0); }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    /** Standard normal (Box–Muller). */
    double gaussian()
    {
        const double u1 = 1.0 - uniform();  // (0, 1]
        const double u2 = uniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
    }

private:
    uint64_t key_;
    uint64_t counter_ = 0;
};

/** Purpose tags keep the streams of different draws apart. */
enum RngTag : uint64_t
{
    kTagFrame = 1,
    kTagJitter,
    kTagTxPhase,
    kTagChain,
    kTagJump,
    kTagTrajectory,
    kTagOdometry,
    kTagNoiseTable,
    kTagSequence,
    kTagTxChain = 0x7478,    //!< transmit chains ("tx"; apart from the sequential tags)
    kTagJumpPhase = 0x6a70,  //!< per-state phase of the jump states ("jp")
    kTagRetry = 0x7274,      //!< 802.11 retries: whether, when, and their draws ("rt")
    kTagChainDelay = 0x6364  //!< receive chains' delays across channels ("cd")
};

}  // namespace mrpt_wifi::sim::detail
