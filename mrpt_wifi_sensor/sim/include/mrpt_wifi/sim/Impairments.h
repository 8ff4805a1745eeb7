/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/sim/Scenario.h>

#include <array>
#include <complex>
#include <cstdint>
#include <map>
#include <ostream>
#include <vector>

namespace mrpt_wifi::sim
{
/** Fixed response of one receive chain on one channel, for one boot of the router. */
struct ChainResponse
{
    double phaseOffset_rad = 0;  //!< constant part
    double gain_dB = 0;
    /** Smooth ripple: φ(k) = Σ_r amplitude_r · cos(π·r·k/(NFFT/2) + phase_r), r = 1..R. */
    std::vector<double> rippleAmplitude_rad, ripplePhase_rad;

    double ripple_rad(int k, unsigned nfft) const;
    /** Total phase at subcarrier k: offset + ripple. */
    double phase_rad(int k, unsigned nfft) const { return phaseOffset_rad + ripple_rad(k, nfft); }
};

/** A change of one chain's jump state at a time. */
struct JumpEvent
{
    double time_s = 0;
    uint8_t state = 0;
};

/** Receiver hardware of one boot: per-channel per-chain phase/gain responses (what
 *  calibration recovers) and the timeline of the 4366c0 inter-antenna jump states.
 *
 * Everything is a pure function of (seed, boot, channel, chain), so any channel can be asked
 * for at any time (the emulator switches channels) with reproducible answers. Responses are
 * cached: not thread-safe. */
class HardwareModel
{
public:
    HardwareModel() = default;
    HardwareModel(
        const ImpairmentSpec& spec, unsigned nRx, uint32_t seed, unsigned boot, double duration_s);

    unsigned boot() const { return boot_; }
    unsigned chains() const { return nRx_; }

    /** Chain response on a channel (centre channel and bandwidth matter, not the sideband). */
    const ChainResponse& chain(const Chanspec& cs, unsigned rx) const;
    /** e^{j φ_i(k)} · 10^{g_i/20} for all NFFT bins of a channel, [rx][bin]. */
    const std::vector<std::complex<float>>& chainFactors(const Chanspec& cs) const;

    /** Delay τ of chain `rx` [s] that moves its phase offset between channels
     *  (ImpairmentSpec::chainPhaseReference). */
    double chainDelay_s(unsigned rx) const;

    /** Jump state of chain `rx` at time t (0 for chain 0 and when jumps are disabled). */
    uint8_t jumpState(unsigned rx, double t_s) const;
    double jumpDelay_s(unsigned rx, double t_s) const;
    /** Delay [s] and own constant phase [rad] (ImpairmentSpec::jumpStatePhase, else 0) of
     *  chain `rx` in jump state `state`: the chain's CSI is multiplied by
     *  e^{−j·2π·f_k·delay}·e^{j·phase}. */
    double jumpStateDelay_s(uint8_t state) const
    {
        return spec_.jumpStateDelays_s.empty() ? state * spec_.jumpStep_s
                                               : spec_.jumpStateDelays_s.at(state);
    }
    double jumpStatePhase_rad(unsigned rx, uint8_t state) const;
    const ImpairmentSpec& spec() const { return spec_; }
    const std::vector<JumpEvent>& jumpEvents(unsigned rx) const { return jumps_.at(rx); }

    bool isDeadCore(unsigned rx) const;

    /** The channels asked for so far (cached), as JSON-friendly data. */
    void writeJson(std::ostream& o, const std::vector<Chanspec>& channels, int indent) const;

private:
    struct ChannelCache
    {
        std::vector<ChainResponse> chains;
        std::vector<std::complex<float>> factors;
    };
    const ChannelCache& cacheFor(const Chanspec& cs) const;

    ImpairmentSpec spec_;
    unsigned nRx_ = 0;
    uint32_t seed_ = 0;
    unsigned boot_ = 0;
    std::vector<std::vector<JumpEvent>> jumps_;       // [rx], sorted by time
    mutable std::map<uint16_t, ChannelCache> cache_;  // key: channel | bandwidth code
};

/** 802.11ac VHT cyclic shift [s] of space-time stream `stream` (0-based): 0, −400, −200, −600,
 *  −350, −650, −100, −750 ns (IEEE 802.11ac Table 22-10, the same for any stream count). */
double vhtCyclicShift_s(unsigned stream);

/** Transmit chains of one multi-stream transmitter for one of its boots: per channel, per chain
 *  a phase and gain (separate RF paths: unknown, fixed per boot and channel), and the cyclic
 *  shift of every space-time stream. Stream m leaves from chain m. A pure function of (seed,
 *  transmitter index, boot, channel, chain); responses cached, not thread-safe. */
class TransmitterHardware
{
public:
    TransmitterHardware() = default;
    TransmitterHardware(
        const ImpairmentSpec& spec, unsigned streams, uint32_t seed, size_t txIndex, unsigned boot);

    unsigned boot() const { return boot_; }
    unsigned streams() const { return streams_; }
    /** False when every factor is 1 (one stream, or everything disabled). */
    bool active() const { return active_; }

    /** Phase and gain of transmit chain m on a channel (no ripple). */
    const ChainResponse& chain(const Chanspec& cs, unsigned m) const;
    /** Cyclic shift of stream m [s] (0 when disabled). */
    double cyclicShift_s(unsigned m) const;
    /** 10^{g_m/20}·e^{jψ_m}·e^{−j2π·k·Δf·T_cs,m} for all NFFT bins, [stream][bin]. */
    const std::vector<std::complex<float>>& streamFactors(const Chanspec& cs) const;

    /** The channels' chains and the cyclic shifts, as JSON. */
    void writeJson(std::ostream& o, const std::vector<Chanspec>& channels, int indent) const;

private:
    struct ChannelCache
    {
        std::vector<ChainResponse> chains;
        std::vector<std::complex<float>> factors;
    };
    const ChannelCache& cacheFor(const Chanspec& cs) const;

    ImpairmentSpec spec_;
    unsigned streams_ = 0;
    uint32_t seed_ = 0;
    size_t txIndex_ = 0;
    unsigned boot_ = 0;
    bool active_ = false;
    mutable std::map<uint16_t, ChannelCache> cache_;
};

/** The per-packet draws of one frame. */
struct PacketImpairments
{
    double samplingTimeOffset_s = 0;  //!< phase −2π·k·Δf·STO on every chain
    double cfoPhase_rad = 0;          //!< common phase
    double agcGain_dB = 0;  //!< common AGC gain relative to the level that meets the target
    std::array<float, 8> chainAgc_dB{};  //!< per chain extra
    std::array<uint8_t, 8> jumpState{};  //!< per chain jump state at the frame time
};

}  // namespace mrpt_wifi::sim
