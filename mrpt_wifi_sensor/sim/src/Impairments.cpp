/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sim/Impairments.h>

#include <algorithm>
#include <cmath>
#include <iomanip>

#include "CounterRng.h"

namespace mrpt_wifi::sim
{
using detail::hashKey;
using detail::seed32;

double ChainResponse::ripple_rad(int k, unsigned nfft) const
{
    const double x = double(k) / (nfft / 2);  // −1..1 across the band
    double r = 0;
    for (size_t i = 0; i < rippleAmplitude_rad.size(); ++i)
        r += rippleAmplitude_rad[i] * std::cos(M_PI * double(i + 1) * x + ripplePhase_rad[i]);
    return r;
}

HardwareModel::HardwareModel(
    const ImpairmentSpec& spec, unsigned nRx, uint32_t seed, unsigned boot, double duration_s)
    : spec_(spec), nRx_(nRx), seed_(seed), boot_(boot), jumps_(nRx)
{
    if (!spec_.antennaJumps || spec_.jumpStates < 2) return;
    // Chain 0 is the reference: the jumps are relative phases between chains.
    for (unsigned rx = 1; rx < nRx_; ++rx)
    {
        mrpt::random::CRandomGenerator rng(seed32(hashKey({seed, detail::kTagJump, boot, rx})));
        auto& ev = jumps_[rx];
        // Until jumpAllowedUntil_s only the allowed states (a drive that misses some).
        const auto& allowed = spec_.jumpAllowedStates;
        const auto restricted = [&](double t)
        { return !allowed.empty() && t < spec_.jumpAllowedUntil_s; };
        uint8_t state = uint8_t(rng.drawUniform32bit() % spec_.jumpStates);
        if (restricted(0)) state = uint8_t(allowed[state % allowed.size()]);
        ev.push_back({0.0, state});
        double t = 0;
        while (spec_.jumpRate_Hz > 0)
        {
            t += -std::log(1.0 - rng.drawUniform(0.0, 1.0)) / spec_.jumpRate_Hz;
            if (t > duration_s) break;
            // Move to one of the other states.
            const uint32_t draw = rng.drawUniform32bit();
            if (restricted(t))
            {
                std::vector<uint8_t> others;
                for (unsigned a : allowed)
                    if (a != state) others.push_back(uint8_t(a));
                if (others.empty()) continue;
                state = others[draw % others.size()];
            }
            else
                state = uint8_t((state + 1 + draw % (spec_.jumpStates - 1)) % spec_.jumpStates);
            ev.push_back({t, state});
        }
    }
}

const HardwareModel::ChannelCache& HardwareModel::cacheFor(const Chanspec& cs) const
{
    const uint16_t key = uint16_t(cs.centerChannel | ((cs.bandwidthMHz / 20) << 8));
    auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;

    // Offsets on the reference channel, which the others follow through the chains' delays.
    const auto& ref = spec_.chainPhaseReference;
    const bool followDelays = spec_.antennaPhaseOffsets && ref && !ref->sameChannel(cs);
    const std::vector<ChainResponse> refChains =
        followDelays ? cacheFor(*ref).chains : std::vector<ChainResponse>();

    ChannelCache c;
    const unsigned nfft = cs.nfft();
    c.chains.resize(nRx_);
    c.factors.resize(size_t(nRx_) * nfft);
    const unsigned R = spec_.rippleComponents;
    for (unsigned rx = 0; rx < nRx_; ++rx)
    {
        mrpt::random::CRandomGenerator rng(
            seed32(hashKey({seed_, detail::kTagChain, boot_, key, rx})));
        ChainResponse& ch = c.chains[rx];
        ch.phaseOffset_rad = spec_.antennaPhaseOffsets ? rng.drawUniform(-M_PI, M_PI) : 0.0;
        ch.gain_dB = rng.drawGaussian1D(0.0, spec_.antennaGainSigma_dB);
        // Σ a_r·cos(...) with a_r ~ N(0, 2σ²/R) has RMS σ.
        const double sigmaTerm = R ? spec_.rippleAmplitude_rad * std::sqrt(2.0 / R) : 0.0;
        for (unsigned r = 0; r < R && spec_.rippleAmplitude_rad > 0; ++r)
        {
            ch.rippleAmplitude_rad.push_back(rng.drawGaussian1D(0.0, sigmaTerm));
            ch.ripplePhase_rad.push_back(rng.drawUniform(-M_PI, M_PI));
        }
        if (followDelays)
            ch.phaseOffset_rad = wrapAngle(
                refChains[rx].phaseOffset_rad -
                2 * M_PI * (cs.centerFrequencyHz() - ref->centerFrequencyHz()) * chainDelay_s(rx));
        const double amp = std::pow(10.0, ch.gain_dB / 20.0);
        for (unsigned bin = 0; bin < nfft; ++bin)
        {
            const int k = binToSubcarrier(bin, nfft);
            c.factors[size_t(rx) * nfft + bin] =
                std::complex<float>(std::polar(amp, ch.phase_rad(k, nfft)));
        }
    }
    return cache_.emplace(key, std::move(c)).first->second;
}

const ChainResponse& HardwareModel::chain(const Chanspec& cs, unsigned rx) const
{
    return cacheFor(cs).chains.at(rx);
}

const std::vector<std::complex<float>>& HardwareModel::chainFactors(const Chanspec& cs) const
{
    return cacheFor(cs).factors;
}

double HardwareModel::chainDelay_s(unsigned rx) const
{
    if (!spec_.chainDelays_s.empty())
        return rx < spec_.chainDelays_s.size() ? spec_.chainDelays_s[rx] : 0.0;
    // A property of the device (its cables and filters), the same at every boot.
    mrpt::random::CRandomGenerator rng(seed32(hashKey({seed_, detail::kTagChainDelay, rx})));
    return rng.drawGaussian1D(0.0, spec_.chainDelaySigma_s);
}

uint8_t HardwareModel::jumpState(unsigned rx, double t_s) const
{
    const auto& ev = jumps_.at(rx);
    if (ev.empty()) return 0;
    auto it = std::upper_bound(
        ev.begin(), ev.end(), t_s, [](double t, const JumpEvent& e) { return t < e.time_s; });
    return it == ev.begin() ? ev.front().state : std::prev(it)->state;
}

double HardwareModel::jumpDelay_s(unsigned rx, double t_s) const
{
    // Chain 0 is the reference and never jumps, whatever delay a listed state 0 has.
    if (jumps_.at(rx).empty()) return 0.0;
    return jumpStateDelay_s(jumpState(rx, t_s));
}

double HardwareModel::jumpStatePhase_rad(unsigned rx, uint8_t state) const
{
    if (!spec_.antennaJumps || !spec_.jumpStatePhase || rx == 0 || state == 0) return 0.0;
    mrpt::random::CRandomGenerator rng(
        seed32(hashKey({seed_, detail::kTagJumpPhase, boot_, rx, state})));
    return rng.drawUniform(-M_PI, M_PI);
}

bool HardwareModel::isDeadCore(unsigned rx) const
{
    return std::find(spec_.deadCores.begin(), spec_.deadCores.end(), rx) != spec_.deadCores.end();
}

void HardwareModel::writeJson(
    std::ostream& o, const std::vector<Chanspec>& channels, int indent) const
{
    const std::string pad(size_t(indent), ' ');
    o << std::setprecision(10);
    o << "{\n" << pad << "  \"boot\": " << boot_ << ",\n";
    o << pad << "  \"channels\": [";
    for (size_t c = 0; c < channels.size(); ++c)
    {
        const Chanspec& cs = channels[c];
        const unsigned nfft = cs.nfft();
        const auto& ks = dataSubcarriers(cs.bandwidthMHz);
        o << (c ? "," : "") << "\n" << pad << "    {\n";
        o << pad << "      \"chanspec\": \"" << cs.asString() << "\",\n";
        o << pad << "      \"data_subcarriers\": [";
        for (size_t i = 0; i < ks.size(); ++i) o << (i ? ", " : "") << ks[i];
        o << "],\n" << pad << "      \"chains\": [";
        for (unsigned rx = 0; rx < nRx_; ++rx)
        {
            const ChainResponse& ch = chain(cs, rx);
            o << (rx ? "," : "") << "\n"
              << pad << "        {\"chain\": " << rx
              << ", \"phase_offset_rad\": " << ch.phaseOffset_rad << ", \"gain_db\": " << ch.gain_dB
              << ", \"ripple_amplitude_rad\": [";
            for (size_t r = 0; r < ch.rippleAmplitude_rad.size(); ++r)
                o << (r ? ", " : "") << ch.rippleAmplitude_rad[r];
            o << "], \"ripple_phase_rad\": [";
            for (size_t r = 0; r < ch.ripplePhase_rad.size(); ++r)
                o << (r ? ", " : "") << ch.ripplePhase_rad[r];
            o << "],\n" << pad << "         \"phase_rad_on_data_subcarriers\": [";
            for (size_t i = 0; i < ks.size(); ++i)
                o << (i ? ", " : "") << ch.phase_rad(ks[i], nfft);
            o << "]}";
        }
        o << "\n" << pad << "      ]\n" << pad << "    }";
    }
    o << "\n" << pad << "  ],\n";
    o << pad << "  \"chain_delay_s\": [";
    for (unsigned rx = 0; rx < nRx_; ++rx) o << (rx ? ", " : "") << chainDelay_s(rx);
    o << "],\n";
    o << pad << "  \"chain_phase_reference\": \""
      << (spec_.chainPhaseReference ? spec_.chainPhaseReference->asString() : std::string())
      << "\",\n";
    o << pad << "  \"jump_step_s\": " << spec_.jumpStep_s << ",\n";
    o << pad << "  \"jump_baseband\": " << (spec_.jumpBaseband ? "true" : "false") << ",\n";
    o << pad << "  \"jump_state_delay_s\": [";
    for (unsigned st = 0; st < (spec_.antennaJumps ? spec_.jumpStates : 1u); ++st)
        o << (st ? ", " : "") << jumpStateDelay_s(uint8_t(st));
    o << "],\n";
    o << pad << "  \"jump_state_phase_rad\": [";
    for (unsigned rx = 0; rx < nRx_; ++rx)
    {
        o << (rx ? ", " : "") << "[";
        for (unsigned st = 0; st < (spec_.antennaJumps ? spec_.jumpStates : 1u); ++st)
            o << (st ? ", " : "") << jumpStatePhase_rad(rx, uint8_t(st));
        o << "]";
    }
    o << "],\n";
    o << pad << "  \"jump_events\": [";
    for (unsigned rx = 0; rx < nRx_; ++rx)
    {
        o << (rx ? ", " : "") << "[";
        for (size_t i = 0; i < jumps_[rx].size(); ++i)
            o << (i ? ", " : "") << "[" << jumps_[rx][i].time_s << ", " << int(jumps_[rx][i].state)
              << "]";
        o << "]";
    }
    o << "]\n" << pad << "}";
}

// ---------------------------------------------------------------------------------------------
double vhtCyclicShift_s(unsigned stream)
{
    static constexpr double kShift_ns[8] = {0, -400, -200, -600, -350, -650, -100, -750};
    return stream < 8 ? kShift_ns[stream] * 1e-9 : 0.0;
}

TransmitterHardware::TransmitterHardware(
    const ImpairmentSpec& spec, unsigned streams, uint32_t seed, size_t txIndex, unsigned boot)
    : spec_(spec), streams_(streams), seed_(seed), txIndex_(txIndex), boot_(boot)
{
    active_ = streams_ > 1 && (spec_.txChainPhaseOffsets || spec_.txChainGainSigma_dB > 0 ||
                               spec_.cyclicShiftDelays);
}

double TransmitterHardware::cyclicShift_s(unsigned m) const
{
    return spec_.cyclicShiftDelays && streams_ > 1 ? vhtCyclicShift_s(m) : 0.0;
}

const TransmitterHardware::ChannelCache& TransmitterHardware::cacheFor(const Chanspec& cs) const
{
    const uint16_t key = uint16_t(cs.centerChannel | ((cs.bandwidthMHz / 20) << 8));
    auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;

    ChannelCache c;
    const unsigned nfft = cs.nfft();
    c.chains.resize(streams_);
    c.factors.resize(size_t(streams_) * nfft);
    for (unsigned m = 0; m < streams_; ++m)
    {
        ChainResponse& ch = c.chains[m];
        if (streams_ > 1)
        {
            mrpt::random::CRandomGenerator rng(
                seed32(hashKey({seed_, detail::kTagTxChain, txIndex_, boot_, key, m})));
            ch.phaseOffset_rad = spec_.txChainPhaseOffsets ? rng.drawUniform(-M_PI, M_PI) : 0.0;
            ch.gain_dB = rng.drawGaussian1D(0.0, spec_.txChainGainSigma_dB);
        }
        const double amp = std::pow(10.0, ch.gain_dB / 20.0);
        const double shift = cyclicShift_s(m);
        for (unsigned bin = 0; bin < nfft; ++bin)
        {
            const int k = binToSubcarrier(bin, nfft);
            c.factors[size_t(m) * nfft + bin] = std::complex<float>(std::polar(
                amp, ch.phaseOffset_rad - 2 * M_PI * double(k) * kSubcarrierSpacingHz * shift));
        }
    }
    return cache_.emplace(key, std::move(c)).first->second;
}

const ChainResponse& TransmitterHardware::chain(const Chanspec& cs, unsigned m) const
{
    return cacheFor(cs).chains.at(m);
}

const std::vector<std::complex<float>>& TransmitterHardware::streamFactors(const Chanspec& cs) const
{
    return cacheFor(cs).factors;
}

void TransmitterHardware::writeJson(
    std::ostream& o, const std::vector<Chanspec>& channels, int indent) const
{
    const std::string pad(size_t(indent), ' ');
    o << std::setprecision(10);
    o << "{\"boot\": " << boot_ << ", \"streams\": " << streams_ << ", \"cyclic_shift_ns\": [";
    for (unsigned m = 0; m < streams_; ++m) o << (m ? ", " : "") << cyclicShift_s(m) * 1e9;
    o << "],\n" << pad << "  \"channels\": [";
    for (size_t c = 0; c < channels.size(); ++c)
    {
        o << (c ? "," : "") << "\n"
          << pad << "    {\"chanspec\": \"" << channels[c].asString() << "\", \"chains\": [";
        for (unsigned m = 0; m < streams_; ++m)
        {
            const ChainResponse& ch = chain(channels[c], m);
            o << (m ? ", " : "") << "{\"chain\": " << m
              << ", \"phase_offset_rad\": " << ch.phaseOffset_rad << ", \"gain_db\": " << ch.gain_dB
              << "}";
        }
        o << "]}";
    }
    o << "\n" << pad << "  ]}";
}

}  // namespace mrpt_wifi::sim
