/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/math/wrap2pi.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>

#include "CounterRng.h"

namespace mrpt_wifi::sim
{
using detail::hashKey;
using detail::seed32;
using mrpt::math::TPoint2D;
using mrpt::math::TPose2D;
using mrpt::math::wrapToPi;

namespace
{
constexpr double kThermalNoise_dBm_per_Hz = -174.0;
// AWGN comes from a table of 2^16 complex Gaussian samples drawn once with mrpt::random: each
// noise value picks an entry by a hash and flips the signs of its parts at random (which keeps
// a circular Gaussian circular). The draws are i.i.d. from that table, at a fraction of the
// cost of Box–Muller per sample; tails stop near 4.5 σ.
constexpr unsigned kNoiseTableBits = 16;

std::string jsonEscape(const std::string& s)
{
    std::string o;
    for (char c : s)
    {
        if (c == '"' || c == '\\') o += '\\';
        if (static_cast<unsigned char>(c) < 0x20) continue;
        o += c;
    }
    return o;
}

// The per-bin loops below run for every pair of every frame: they are written so that they
// vectorise and are built for AVX2 as well as the baseline (picked at load time).

/** dst[b] = factor[b] · h[b], written out (std::complex multiplication carries NaN/inf
 *  handling that keeps compilers from vectorising it). */
__attribute__((target_clones("avx2", "default"))) void applyChainFactors(
    const std::complex<float>* h, const std::complex<float>* factor, unsigned n,
    std::complex<float>* dst)
{
    const float* __restrict hf = reinterpret_cast<const float*>(h);
    const float* __restrict ff = reinterpret_cast<const float*>(factor);
    float* __restrict df = reinterpret_cast<float*>(dst);
    for (unsigned b = 0; b < n; ++b)
    {
        const float hr = hf[2 * b], hi = hf[2 * b + 1], fr = ff[2 * b], fi = ff[2 * b + 1];
        df[2 * b] = fr * hr - fi * hi;
        df[2 * b + 1] = fr * hi + fi * hr;
    }
}

/** Σ |h_b|² over n values (float lanes, double total). */
__attribute__((target_clones("avx2", "default"))) double sumOfSquares(
    const std::complex<float>* h, unsigned n)
{
    const float* f = reinterpret_cast<const float*>(h);
    float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    unsigned i = 0;
    for (; i + 8 <= 2 * n; i += 8)
        for (unsigned l = 0; l < 8; ++l) acc[l] += f[i + l] * f[i + l];
    double total = 0;
    for (; i < 2 * n; ++i) total += double(f[i]) * f[i];
    for (float a : acc) total += a;
    return total;
}

/** dst[b] += scale · w_b, w_b i.i.d. unit complex Gaussian: a table entry picked by a hash of
 *  (salt, b), with random signs of its real and imaginary parts (circular symmetry). Integer
 *  operations on the float bits, no branches: the loops vectorise (AVX2 gathers the table). */
__attribute__((target_clones("avx2", "default"))) void addTableNoise(
    const uint32_t* __restrict tableRe, const uint32_t* __restrict tableIm, uint32_t salt,
    float scale, unsigned n, uint32_t* __restrict scratchRe, uint32_t* __restrict scratchIm,
    std::complex<float>* dst)
{
    for (unsigned b = 0; b < n; ++b)
    {
        const uint32_t h = detail::mix32(salt + b * 0xc2b2ae35u);
        const uint32_t index = h >> (32 - kNoiseTableBits);
        scratchRe[b] = tableRe[index] ^ ((h & 1u) << 31);
        scratchIm[b] = tableIm[index] ^ ((h & 2u) << 30);
    }
    float* __restrict out = reinterpret_cast<float*>(dst);
    for (unsigned b = 0; b < n; ++b)
    {
        float re, im;
        std::memcpy(&re, scratchRe + b, sizeof(float));
        std::memcpy(&im, scratchIm + b, sizeof(float));
        out[2 * b] += scale * re;
        out[2 * b + 1] += scale * im;
    }
}

/** The robot's body shadows the paths arriving from behind it (ReceiverSpec::BodyShadow). */
void applyBodyShadow(
    const ReceiverSpec::BodyShadow& body, double sensorYaw_rad, std::vector<PropagationPath>& paths)
{
    if (body.attenuation_dB <= 0) return;
    for (auto& p : paths)
    {
        const double loss = body.loss_dB(p.arrival_rad - sensorYaw_rad);
        if (loss <= 0) continue;
        p.gain *= std::pow(10.0, -loss / 20.0);
        p.crossingLoss_dB += loss;
    }
}

double dB2power(double dB)
{
    return std::pow(10.0, dB / 10.0);
}
double dB2amplitude(double dB)
{
    return std::pow(10.0, dB / 20.0);
}
}  // namespace

Simulator::Simulator(Scenario scenario) : sc_(std::move(scenario))
{
    sc_.validate();
    channel_ = ChannelModel(sc_);

    mrpt::random::CRandomGenerator trajRng(seed32(hashKey({sc_.seed, detail::kTagTrajectory})));
    trajectory_ = Trajectory::generate(sc_, trajRng);
    mrpt::random::CRandomGenerator odoRng(seed32(hashKey({sc_.seed, detail::kTagOdometry})));
    odometry_ = simulateOdometry(trajectory_, sc_.odometry, odoRng);

    for (size_t i = 0; i < sc_.transmitters.size(); ++i)
    {
        const auto& t = sc_.transmitters[i];
        TransmitterState st;
        st.images = channel_.imagesOf({t.pose.x, t.pose.y});
        st.framePeriod_s = 1.0 / t.frameRate_Hz;
        detail::CounterRng rng(hashKey({sc_.seed, detail::kTagTxPhase, i}));
        st.phase_s = rng.uniform() * st.framePeriod_s;
        st.hardware = TransmitterHardware(sc_.impairments, t.streams, sc_.seed, i, 0);
        tx_.push_back(st);
    }
    hardware_ = HardwareModel(
        sc_.impairments, unsigned(sc_.receiver.array.size()), sc_.seed, 0, sc_.duration_s);

    mrpt::random::CRandomGenerator noiseRng(seed32(hashKey({sc_.seed, detail::kTagNoiseTable})));
    // Float bit patterns of N(0, 1/2) samples (E|n|² = 1), real and imaginary parts apart.
    const size_t tableSize = size_t(1) << kNoiseTableBits;
    noiseTableRe_.resize(tableSize);
    noiseTableIm_.resize(tableSize);
    for (size_t i = 0; i < tableSize; ++i)
    {
        const float re = float(noiseRng.drawGaussian1D(0, std::sqrt(0.5)));
        const float im = float(noiseRng.drawGaussian1D(0, std::sqrt(0.5)));
        std::memcpy(&noiseTableRe_[i], &re, sizeof(float));
        std::memcpy(&noiseTableIm_[i], &im, sizeof(float));
    }
    rewind(0);
}

mrpt::Clock::time_point Simulator::timestampAt(double t_s) const
{
    return mrpt::Clock::fromDouble(sc_.startTime_unix + t_s);
}

double Simulator::frameTime(size_t tx, uint64_t n) const
{
    const auto& st = tx_.at(tx);
    const double jitter =
        sc_.impairments.timingJitter *
        detail::CounterRng(hashKey({sc_.seed, detail::kTagJitter, tx, n})).uniform();
    return st.phase_s + (double(n) + jitter) * st.framePeriod_s;
}

uint64_t Simulator::firstFrameAtOrAfter(size_t tx, double t_s) const
{
    const auto& st = tx_.at(tx);
    const double approx = std::floor((t_s - st.phase_s) / st.framePeriod_s) - 1.0;
    uint64_t n = approx > 0 ? uint64_t(approx) : 0;
    while (frameTime(tx, n) < t_s) ++n;
    return n;
}

void Simulator::rewind(double t_s)
{
    nextOdometry_ = size_t(
        std::lower_bound(
            odometry_.begin(), odometry_.end(), t_s,
            [](const OdometrySample& s, double t) { return s.time_s < t; }) -
        odometry_.begin());
    for (size_t i = 0; i < tx_.size(); ++i)
    {
        tx_[i].nextFrame = firstFrameAtOrAfter(i, t_s);
        tx_[i].retryTime_s = std::numeric_limits<double>::infinity();
    }
    streamTime_ = t_s;
}

void Simulator::reboot()
{
    hardware_ = HardwareModel(
        sc_.impairments, unsigned(sc_.receiver.array.size()), sc_.seed, hardware_.boot() + 1,
        sc_.duration_s);
}

void Simulator::rebootTransmitter(size_t tx)
{
    auto& st = tx_.at(tx);
    st.hardware = TransmitterHardware(
        sc_.impairments, sc_.transmitters[tx].streams, sc_.seed, tx, st.hardware.boot() + 1);
}

bool Simulator::hears(size_t tx) const
{
    if (!channelFilter_) return true;
    const Chanspec& cs = sc_.transmitters[tx].chanspec;
    return cs.centerChannel == channelFilter_->centerChannel &&
           cs.bandwidthMHz == channelFilter_->bandwidthMHz;
}

bool Simulator::heardAt(size_t tx, double t_s) const
{
    return sc_.receiver.nextListeningTime(sc_.transmitters[tx].chanspec, t_s) == t_s;
}

bool Simulator::skipToHeardFrame(size_t tx)
{
    auto& st = tx_[tx];
    for (;;)
    {
        const double t = frameTime(tx, st.nextFrame);
        const double opens = sc_.receiver.nextListeningTime(sc_.transmitters[tx].chanspec, t);
        if (opens == t) return true;
        if (!(opens <= sc_.duration_s)) return false;
        st.nextFrame = firstFrameAtOrAfter(tx, opens);
    }
}

double Simulator::retryDelay(size_t tx, uint64_t n) const
{
    if (sc_.impairments.retryProbability <= 0) return -1;
    detail::CounterRng rng(hashKey({sc_.seed, detail::kTagRetry, tx, n}));
    if (rng.uniform() >= sc_.impairments.retryProbability) return -1;
    return rng.uniform(20e-6, 7e-3);  // what the muTrack captures show
}

bool Simulator::next(SimEvent& ev)
{
    double best = std::numeric_limits<double>::infinity();
    int source = -2;  // -1: odometry, >= 0: transmitter
    bool retry = false;
    if (odometryEnabled_ && nextOdometry_ < odometry_.size())
    {
        best = odometry_[nextOdometry_].time_s;
        source = -1;
    }
    const bool scheduled = followSchedule_ && !sc_.receiver.channelSchedule.empty();
    for (size_t i = 0; i < tx_.size(); ++i)
    {
        if (!hears(i)) continue;
        // A transmitter that was filtered out resumes at the stream's present, not its past.
        if (frameTime(i, tx_[i].nextFrame) < streamTime_)
            tx_[i].nextFrame = firstFrameAtOrAfter(i, streamTime_);
        const double t = !scheduled || skipToHeardFrame(i)
                             ? frameTime(i, tx_[i].nextFrame)
                             : std::numeric_limits<double>::infinity();
        if (t < best)
        {
            best = t;
            source = int(i);
            retry = false;
        }
        if (tx_[i].retryTime_s < best)
        {
            best = tx_[i].retryTime_s;
            source = int(i);
            retry = true;
        }
    }
    if (source == -2 || best > sc_.duration_s) return false;
    streamTime_ = best;
    ev.time_s = best;
    ev.truePose = trajectory_.poseAt(best);

    if (source == -1)
    {
        const OdometrySample& s = odometry_[nextOdometry_++];
        ev.kind = SimEvent::Kind::Odometry;
        if (!ev.odometry || ev.odometry.use_count() > 1)
            ev.odometry = std::make_shared<mrpt::obs::CObservationOdometry>();
        auto& o = *ev.odometry;
        o.timestamp = timestampAt(s.time_s);
        o.sensorLabel = sc_.odometry.sensorLabel;
        o.odometry = mrpt::poses::CPose2D(s.odometry);
        o.hasVelocities = true;
        o.velocityLocal = s.velocityLocal;
        o.hasEncodersInfo = false;
        return true;
    }

    ev.kind = SimEvent::Kind::Csi;
    if (!ev.csi || ev.csi.use_count() > 1) ev.csi = std::make_shared<CObservationWiFiCSI>();
    auto& st = tx_[size_t(source)];
    if (retry)
    {
        synthesizeFrame(size_t(source), st.retryFrame, *ev.csi, ev.frame, 1);
        st.retryTime_s = std::numeric_limits<double>::infinity();
        return true;
    }
    const uint64_t n = st.nextFrame++;
    synthesizeFrame(size_t(source), n, *ev.csi, ev.frame);
    if (const double d = retryDelay(size_t(source), n);
        d >= 0 && (!scheduled || heardAt(size_t(source), best + d)))
    {
        st.retryFrame = n;
        st.retryTime_s = best + d;
    }
    return true;
}

TPose2D Simulator::sensorPoseInWorld(const TPose2D& robotPose) const
{
    const auto& sp = sc_.receiver.sensorPose;
    return robotPose + TPose2D(sp.x(), sp.y(), sp.yaw());
}

std::vector<PropagationPath> Simulator::pathsAt(size_t tx, const TPose2D& robotPose) const
{
    const TPose2D s = sensorPoseInWorld(robotPose);
    std::vector<PropagationPath> out;
    const double lambda = kSpeedOfLight / sc_.transmitters.at(tx).chanspec.centerFrequencyHz();
    channel_.computePaths(tx_.at(tx).images, {s.x, s.y}, lambda, out);
    applyBodyShadow(sc_.receiver.bodyShadow, s.phi, out);
    return out;
}

void Simulator::synthesizeFrame(
    size_t txIndex, uint64_t n, CObservationWiFiCSI& out, FrameTruth& truth, unsigned reception)
{
    const TransmitterSpec& tx = sc_.transmitters.at(txIndex);
    const ReceiverSpec& rxSpec = sc_.receiver;
    const ImpairmentSpec& imp = sc_.impairments;
    const Chanspec& cs = tx.chanspec;
    const unsigned nfft = cs.nfft();
    const unsigned nRx = unsigned(rxSpec.array.size());
    const unsigned nTx = tx.streams;
    const double fc = cs.centerFrequencyHz();
    const double t =
        frameTime(txIndex, n) + (reception ? std::max(0.0, retryDelay(txIndex, n)) : 0.0);

    // --- geometry and the ideal channel
    truth.transmitterIndex = txIndex;
    truth.frameIndex = n;
    truth.reception = reception;
    truth.time_s = t;
    truth.robotPose = trajectory_.poseAt(t);
    truth.sensorPose = sensorPoseInWorld(truth.robotPose);
    const TPoint2D rxPoint{truth.sensorPose.x, truth.sensorPose.y};
    channel_.computePaths(tx_[txIndex].images, rxPoint, kSpeedOfLight / fc, paths_);
    applyBodyShadow(rxSpec.bodyShadow, truth.sensorPose.phi, paths_);
    synthesizer_.synthesize(
        paths_, ArrayPlacement{&rxSpec.array, truth.sensorPose.phi, nRx},
        ArrayPlacement{&tx.array, tx.pose.phi, nTx}, cs, ideal_);

    // --- truth about the geometry
    const PropagationPath& los = paths_.front();
    truth.aoa_rad = wrapToPi(los.arrival_rad - truth.sensorPose.phi);
    truth.aod_rad = wrapToPi(los.departure_rad - tx.pose.phi);
    truth.losDistance_m = los.length_m;
    truth.losDelay_s = los.delay_s;
    truth.losCrossingLoss_dB = los.crossingLoss_dB;
    double others = 0;
    size_t strongest = 0;
    for (size_t i = 1; i < paths_.size(); ++i)
    {
        others += std::norm(paths_[i].gain);
        if (std::abs(paths_[i].gain) > std::abs(paths_[strongest].gain)) strongest = i;
    }
    truth.kFactor_dB = others > 0 ? 10 * std::log10(std::norm(los.gain) / others) : 300.0;
    truth.strongestPathAoa_rad = wrapToPi(paths_[strongest].arrival_rad - truth.sensorPose.phi);
    truth.pathCount = unsigned(paths_.size());

    // --- link budget: received power over the occupied band, SNR, RSSI
    const int edge = CsiSynthesizer::occupiedEdge(cs.bandwidthMHz);
    double meanPower = 0;
    for (unsigned q = 0; q < nTx * nRx; ++q)
        meanPower += sumOfSquares(
            ideal_.data() + size_t(q) * nfft + subcarrierToBin(-edge, nfft),
            unsigned(2 * edge + 1));
    meanPower /= double(nTx * nRx) * (2 * edge + 1);
    meanPower = std::max(meanPower, 1e-30);
    truth.rxPower_dBm =
        tx.txPower_dBm + tx.antennaGain_dBi + rxSpec.antennaGain_dBi + 10 * std::log10(meanPower);
    const double noiseFloor_dBm =
        kThermalNoise_dBm_per_Hz + 10 * std::log10(cs.bandwidthMHz * 1e6) + rxSpec.noiseFigure_dB;
    if (imp.fixedSnr_dB)
        truth.snr_dB = *imp.fixedSnr_dB;
    else
    {
        const double thermal = dB2power(truth.rxPower_dBm - noiseFloor_dBm);
        truth.snr_dB = -10 * std::log10(1 / thermal + 1 / dB2power(imp.snrCap_dB));
    }

    // --- per-packet draws (pure function of seed, transmitter, frame)
    // A retry is another reception: its own noise, sampling-time offset and CFO.
    detail::CounterRng rng(
        reception ? hashKey({sc_.seed, detail::kTagRetry, txIndex, n, reception})
                  : hashKey({sc_.seed, detail::kTagFrame, txIndex, n}));
    PacketImpairments& pk = truth.packet;
    pk = PacketImpairments();
    pk.samplingTimeOffset_s = imp.samplingTimeOffsetSigma_s * rng.gaussian();
    pk.cfoPhase_rad = imp.cfoCommonPhase ? rng.uniform(-M_PI, M_PI) : 0.0;
    pk.agcGain_dB = imp.agcSigma_dB * rng.gaussian();
    for (unsigned i = 0; i < nRx; ++i)
    {
        pk.chainAgc_dB[i] = float(imp.agcPerChainSigma_dB * rng.gaussian());
        pk.jumpState[i] = hardware_.jumpState(i, t);
    }
    const double rssi = truth.rxPower_dBm + imp.rssiSigma_dB * rng.gaussian();
    truth.rssi_dBm = int8_t(std::clamp(std::lround(rssi), -127L, -1L));
    const uint32_t noiseKey = uint32_t(rng.nextU64());

    // --- AGC: the reported CSI has RMS ≈ agcTarget whatever the path loss
    const double snrLinear = dB2power(truth.snr_dB);
    const double noisePower = imp.awgn ? meanPower / snrLinear : 0.0;
    const double agc =
        imp.agcTarget / std::sqrt(meanPower + noisePower) * dB2amplitude(pk.agcGain_dB);

    // --- per chain, per bin factor: AGC, chain response, STO, CFO, jump delay, sub-band sign
    rxFactors_.resize(size_t(nRx) * nfft);
    const auto& chains = hardware_.chainFactors(cs);
    const int kFirst = -int(nfft / 2);
    for (unsigned i = 0; i < nRx; ++i)
    {
        const double gain = agc * dB2amplitude(pk.chainAgc_dB[i]);
        const double delay = pk.samplingTimeOffset_s;  // baseband: phase −2π·k·Δf·STO
        // RF: phase −2π·f_k·τ_jump; a baseband sample slip: −2π·k·Δf·τ_jump.
        const double jump = hardware_.jumpDelay_s(i, t);
        const double jumpFrom = imp.jumpBaseband ? 0.0 : fc;
        const double jumpPhase = hardware_.jumpStatePhase_rad(i, pk.jumpState[i]);
        // Start at the lowest bin and step with one complex multiply per bin.
        std::complex<double> f = std::polar(
            gain, pk.cfoPhase_rad + jumpPhase - 2 * M_PI * (kFirst * kSubcarrierSpacingHz * delay) -
                      2 * M_PI * std::fmod((jumpFrom + kFirst * kSubcarrierSpacingHz) * jump, 1.0));
        const std::complex<double> step =
            std::polar(1.0, -2 * M_PI * kSubcarrierSpacingHz * (delay + jump));
        for (unsigned bin = 0; bin < nfft; ++bin)
        {
            std::complex<float> v = std::complex<float>(f) * chains[size_t(i) * nfft + bin];
            if (imp.lowerSubbandSignFlip &&
                inNegatedSubband(binToSubcarrier(bin, nfft), cs.bandwidthMHz))
                v = -v;
            rxFactors_[size_t(i) * nfft + bin] = v;
            f *= step;
        }
    }

    // --- the observation
    out.timestamp = timestampAt(t);
    out.sensorLabel = rxSpec.sensorLabel;
    out.sensorPose = rxSpec.sensorPose;
    out.transmitter = tx.mac;
    out.rssi_dBm = truth.rssi_dBm;
    truth.sequenceNumber = uint16_t((tx.firstSequenceNumber + n) % 4096);
    out.sequenceNumber = truth.sequenceNumber;
    out.fragmentNumber = 0;
    out.frameControl = 0;
    out.chanspec = cs;
    out.chipId = rxSpec.chipId;
    out.firmwareCounter = 0;
    out.headerVariant = NexmonHeaderVariant::Nexmon;
    out.routerAddress = "sim";
    out.maskedBins.clear();
    out.subcarrierIndices.clear();
    out.resize(nTx, nRx, nfft);

    const double noiseRms = std::sqrt(noisePower);  // before the receive chain's gains
    const uint32_t frameSalt = noiseKey * 0x9e3779b9u;
    noiseScratchRe_.resize(nfft);
    noiseScratchIm_.resize(nfft);
    const TransmitterHardware& txHw = tx_[txIndex].hardware;
    const std::vector<std::complex<float>>* txFactors =
        txHw.active() ? &txHw.streamFactors(cs) : nullptr;
    if (txHw.active()) txScratch_.resize(nfft);
    for (unsigned m = 0; m < nTx; ++m)
        for (unsigned i = 0; i < nRx; ++i)
        {
            const bool dead = hardware_.isDeadCore(i);
            out.setPresent(m, i, !(dead && imp.deadCoresMissing));
            if (dead) continue;  // zeros
            const size_t q = size_t(m) * nRx + i;
            const std::complex<float>* h = ideal_.data() + q * nfft;
            if (txHw.active())
            {
                // Transmit chain m and the stream's cyclic shift first, then the receive chain.
                applyChainFactors(h, txFactors->data() + size_t(m) * nfft, nfft, txScratch_.data());
                h = txScratch_.data();
            }
            applyChainFactors(h, rxFactors_.data() + size_t(i) * nfft, nfft, out.pair(m, i));
            if (noiseRms <= 0) continue;
            // The noise passes the chain's gains (AGC included) like the signal does.
            const float chainScale =
                float(noiseRms * std::abs(rxFactors_[size_t(i) * nfft + nfft / 2]));
            addTableNoise(
                noiseTableRe_.data(), noiseTableIm_.data(), frameSalt + uint32_t(q) * 0x85ebca6bu,
                chainScale, nfft, noiseScratchRe_.data(), noiseScratchIm_.data(), out.pair(m, i));
        }

    if (rxSpec.csiFormat == CsiFormat::Intel5300)
    {
        toIntel5300(out);
        return;
    }

    // The firmware writes PHY status words over a few bins: garbage of data-like magnitude.
    if (imp.firmwareOverwrittenBins)
        for (int k : firmwareOverwrittenSubcarriers(cs.bandwidthMHz))
            for (unsigned m = 0; m < nTx; ++m)
                for (unsigned i = 0; i < nRx; ++i)
                {
                    if (hardware_.isDeadCore(i)) continue;
                    const double mag = imp.agcTarget * rng.uniform(0.0, 4.0);
                    out.at(m, i, subcarrierToBin(k, nfft)) =
                        std::complex<float>(std::polar(mag, rng.uniform(-M_PI, M_PI)));
                }
}

void Simulator::toIntel5300(CObservationWiFiCSI& out)
{
    // What the CSI Tool reports: the 30 grouped subcarriers, int8 I/Q. The scale puts the RMS
    // of a complex value at 20, as in the tool's logs; the rounding is the quantisation noise.
    constexpr double kRms = 20.0;
    const unsigned nfft = out.nfft();
    const auto& ks = htGroupedSubcarriers(out.chanspec.bandwidthMHz);
    double power = 0;
    for (unsigned m = 0; m < out.nTx; ++m)
        for (unsigned i = 0; i < out.nRx; ++i)
            for (int k : ks) power += std::norm(out.at(m, i, subcarrierToBin(k, nfft)));
    power /= double(out.nTx * out.nRx * ks.size());
    const float scale = power > 0 ? float(kRms / std::sqrt(power)) : 0.f;
    const auto q = [](float x) { return std::clamp(std::round(x), -128.f, 127.f); };
    for (unsigned m = 0; m < out.nTx; ++m)
        for (unsigned i = 0; i < out.nRx; ++i)
        {
            auto* p = out.pair(m, i);
            intelScratch_.assign(nfft, {0.f, 0.f});
            for (int k : ks)
            {
                const unsigned b = subcarrierToBin(k, nfft);
                intelScratch_[b] = {q(p[b].real() * scale), q(p[b].imag() * scale)};
            }
            std::copy(intelScratch_.begin(), intelScratch_.end(), p);
        }
    out.subcarrierIndices.assign(ks.begin(), ks.end());
    out.source = "iwl5300";
    out.chipId = 0;
}

void Simulator::writeImpairmentsJson(std::ostream& o) const
{
    const auto& imp = sc_.impairments;
    std::vector<Chanspec> channels;
    for (const auto& t : sc_.transmitters)
    {
        const bool seen = std::any_of(
            channels.begin(), channels.end(),
            [&](const Chanspec& c)
            {
                return c.centerChannel == t.chanspec.centerChannel &&
                       c.bandwidthMHz == t.chanspec.bandwidthMHz;
            });
        if (!seen) channels.push_back(t.chanspec);
    }
    o << std::setprecision(10);
    o << "{\n";
    o << "  \"scenario\": \"" << jsonEscape(sc_.name) << "\",\n";
    o << "  \"seed\": " << sc_.seed << ",\n";
    o << "  \"conventions\": \"CSI per chain i is multiplied by 10^(gain_db/20)·exp(j·phase(k)),"
         " phase(k) = phase_offset_rad + Σ_r ripple_amplitude_rad[r]·cos(π·(r+1)·k/(NFFT/2) +"
         " ripple_phase_rad[r]); per packet: exp(-j·2π·k·312.5e3·sto_s + j·cfo_phase_rad), and"
         " exp(-j·2π·f_k·jump_state_delay_s[state]) for a chain in jump state 'state' (state·"
         "jump_step_s unless the scenario lists the states' delays; f_k − f_c instead of f_k"
         " when jump_baseband is true). Per-packet"
         " values are in frames.csv.\",\n";
    o << "  \"hardware\": ";
    hardware_.writeJson(o, channels, 2);
    o << ",\n  \"transmit_conventions\": \"CSI of transmit stream m is multiplied by"
         " 10^(gain_db/20)·exp(j·phase_offset_rad) of transmit chain m on the transmitter's"
         " channel and by exp(-j·2π·k·312.5e3·cyclic_shift_ns·1e-9) (802.11ac VHT cyclic shift)."
         " Only multi-stream transmitters.\",\n";
    o << "  \"transmitters\": [";
    for (size_t t = 0; t < sc_.transmitters.size(); ++t)
    {
        const auto& spec = sc_.transmitters[t];
        o << (t ? "," : "") << "\n    {\"name\": \"" << jsonEscape(spec.name) << "\", \"mac\": \""
          << spec.mac.asString() << "\", \"hardware\": ";
        tx_[t].hardware.writeJson(o, {spec.chanspec}, 4);
        o << "}";
    }
    o << "\n  ]";
    o << ",\n  \"per_packet\": {\"sto_sigma_s\": " << imp.samplingTimeOffsetSigma_s
      << ", \"cfo_common_phase\": " << (imp.cfoCommonPhase ? "true" : "false")
      << ", \"agc_target\": " << imp.agcTarget << ", \"agc_sigma_db\": " << imp.agcSigma_dB
      << ", \"agc_per_chain_sigma_db\": " << imp.agcPerChainSigma_dB
      << ", \"rssi_sigma_db\": " << imp.rssiSigma_dB
      << ", \"awgn\": " << (imp.awgn ? "true" : "false") << ", \"snr_cap_db\": " << imp.snrCap_dB
      << ", \"fixed_snr_db\": ";
    if (imp.fixedSnr_dB)
        o << *imp.fixedSnr_dB;
    else
        o << "null";
    o << "},\n  \"dead_cores\": [";
    for (size_t i = 0; i < imp.deadCores.size(); ++i) o << (i ? ", " : "") << imp.deadCores[i];
    o << "],\n  \"dead_cores_missing\": " << (imp.deadCoresMissing ? "true" : "false")
      << ",\n  \"firmware_overwritten_bins\": " << (imp.firmwareOverwrittenBins ? "true" : "false")
      << ",\n  \"lower_subband_sign_flip\": " << (imp.lowerSubbandSignFlip ? "true" : "false")
      << "\n}\n";
}

}  // namespace mrpt_wifi::sim
