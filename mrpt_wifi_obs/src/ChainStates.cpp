/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/ChainStates.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace mrpt_wifi
{
namespace
{
/** |Σ_k z_k·e^{j·2π·Δf·k·τ}|², with e^{j·w·k} by recurrence along consecutive subcarriers. */
double crossSpectrumPower(const Eigen::VectorXcd& z, const std::vector<int>& k, double tau_s)
{
    const double w = 2 * M_PI * kSubcarrierSpacingHz * tau_s;
    const std::complex<double> step = std::polar(1.0, w);
    std::complex<double> rot = std::polar(1.0, w * k[0]), acc{0, 0};
    for (Eigen::Index j = 0; j < z.size(); ++j)
    {
        if (j > 0)
            rot = k[size_t(j)] - k[size_t(j - 1)] == 1 ? rot * step
                                                       : std::polar(1.0, w * k[size_t(j)]);
        acc += z(j) * rot;
    }
    return std::norm(acc);
}

/** The highest point of the cross-spectrum power on a grid `from`, `from + step`, ... (n
 *  points), refined by a parabola through it and its neighbours. */
double peakOnGrid(
    const Eigen::VectorXcd& z, const std::vector<int>& k, double from_s, double step_s, int n,
    double* peakPower = nullptr)
{
    std::vector<double> power(static_cast<size_t>(n));
    for (int g = 0; g < n; ++g) power[size_t(g)] = crossSpectrumPower(z, k, from_s + g * step_s);
    const size_t best = size_t(std::max_element(power.begin(), power.end()) - power.begin());
    double offset = 0;
    if (best > 0 && best + 1 < power.size())
    {
        const double a = power[best - 1], b = power[best], c = power[best + 1];
        const double den = a - 2 * b + c;
        if (den < 0) offset = std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
    }
    if (peakPower) *peakPower = power[best];
    return from_s + (double(best) + offset) * step_s;
}

/** The inter-chain delay from the cross spectrum z_k = Σ_m h_{m,i}(k)·h_{m,0}(k)^*, starting
 *  from the phase-slope estimate `slopeDelay_s`. Where that estimate sits on a strong lobe of
 *  the delay profile |Σ_k z_k·e^{j2π·Δf·k·τ}| (at least half the global peak within ±25 ns at
 *  80 MHz), the lobe's own peak near it (±3 ns) refines it: the slope's centroid stays with the
 *  main path under multipath, the peak adds precision. Otherwise (low SNR: the neighbouring
 *  products are too noisy for the slope, which then strays by several ns) the global peak,
 *  where all subcarriers add coherently. The lobes, the states and so the windows are `scale`
 *  (80/bandwidth) times wider at narrower bandwidths. */
double crossSpectrumDelay(
    const Eigen::MatrixXcf& products, const std::vector<int>& k, double slopeDelay_s, double scale)
{
    const Eigen::VectorXcd z = products.cast<std::complex<double>>().colwise().sum().transpose();
    double globalPower = 0;
    const double reach_s = 25e-9 * scale;
    const double global = peakOnGrid(z, k, -reach_s, 1e-9 * scale, 51, &globalPower);
    if (std::abs(slopeDelay_s) < reach_s &&
        crossSpectrumPower(z, k, slopeDelay_s) >= 0.5 * globalPower)
        return peakOnGrid(z, k, slopeDelay_s - 3e-9 * scale, 0.5e-9 * scale, 13);
    return global;
}
}  // namespace

double chainStateDelayScale(unsigned bandwidthMHz)
{
    return bandwidthMHz > 0 ? 80.0 / double(bandwidthMHz) : 1.0;
}

unsigned bandwidthOfSubcarriers(const std::vector<int>& k)
{
    int widest = 0;
    for (int x : k) widest = std::max(widest, std::abs(x));
    // 20 MHz spans |k| ≤ 32, 40 MHz ≤ 64, 80 MHz ≤ 128 (FFT halves of 64/128/256 bins).
    return widest <= 32 ? 20u : widest <= 64 ? 40u : widest <= 128 ? 80u : 160u;
}

void measureChainDelays(
    const Eigen::Ref<const Eigen::MatrixXcf>& H, unsigned nRx, const std::vector<int>& k,
    std::vector<double>& delays_s, std::vector<double>& coherence)
{
    delays_s.assign(nRx, 0.0);
    coherence.assign(nRx, nRx > 0 ? 1.0 : 0.0);
    if (nRx < 2 || H.rows() % nRx != 0 || H.cols() < 2) return;
    const Eigen::Index streams = H.rows() / Eigen::Index(nRx);
    const double scale = chainStateDelayScale(bandwidthOfSubcarriers(k));
    Eigen::MatrixXcf products(streams, H.cols());
    for (unsigned i = 1; i < nRx; ++i)
    {
        for (Eigen::Index m = 0; m < streams; ++m)
            products.row(m) = H.row(m * nRx + i).cwiseProduct(H.row(m * nRx).conjugate());
        // Coherence of neighbouring subcarriers' products: 1 for a clean delay, ~0 for noise.
        std::complex<double> acc{0, 0};
        double magnitude = 0;
        for (Eigen::Index m = 0; m < streams; ++m)
            for (Eigen::Index j = 1; j < H.cols(); ++j)
            {
                const std::complex<double> z = std::complex<double>(products(m, j)) *
                                               std::conj(std::complex<double>(products(m, j - 1)));
                acc += z;
                magnitude += std::abs(z);
            }
        const double slope = CsiPreprocessor::estimatePhaseSlope(products, k);
        delays_s[i] = -slope / (2 * M_PI * kSubcarrierSpacingHz);
        coherence[i] = magnitude > 0 ? std::abs(acc) / magnitude : 0.0;
        // Strong signals (coherence ≥ 0.97, about 20 dB and up) keep the phase slope, which
        // stays with the main path under multipath; weaker ones (0.83–0.93 at 10 dB) take the
        // cross spectrum's delay profile, where the slope strays by several ns.
        constexpr double kSlopeCoherence = 0.97;
        if (coherence[i] < kSlopeCoherence)
            delays_s[i] = crossSpectrumDelay(products, k, delays_s[i], scale);
    }
}

bool measureChainDelays(
    const CObservationWiFiCSI& obs, const SubcarrierLayout& layout, std::vector<double>& delays_s,
    std::vector<double>& coherence)
{
    const unsigned nRx = obs.nRx;
    if (nRx < 2 || obs.csi.size() < size_t(obs.nTx) * nRx * obs.nfft()) return false;
    std::vector<size_t> columns;
    std::vector<int> k;
    for (size_t j = 0; j < layout.size(); ++j)
        if (std::find(obs.maskedBins.begin(), obs.maskedBins.end(), layout.bins[j]) ==
            obs.maskedBins.end())
        {
            columns.push_back(j);
            k.push_back(layout.subcarriers[j]);
        }
    std::vector<unsigned> complete;
    for (unsigned m = 0; m < obs.nTx; ++m)
    {
        bool all = true;
        for (unsigned i = 0; i < nRx && all; ++i) all = obs.isPresent(m, i);
        if (all) complete.push_back(m);
    }
    if (complete.empty() || k.size() < 2) return false;
    Eigen::MatrixXcf H(Eigen::Index(complete.size() * nRx), Eigen::Index(k.size()));
    for (size_t s = 0; s < complete.size(); ++s)
        for (unsigned i = 0; i < nRx; ++i)
        {
            const auto* p = obs.pair(complete[s], i);
            for (size_t c = 0; c < columns.size(); ++c)
                H(Eigen::Index(s * nRx + i), Eigen::Index(c)) = p[layout.bins[columns[c]]];
        }
    measureChainDelays(H, nRx, k, delays_s, coherence);
    return true;
}

const char* toString(ChainStateOrigin o)
{
    switch (o)
    {
        case ChainStateOrigin::Calibration:
            return "calibrated";
        case ChainStateOrigin::Assumed:
            return "assumed calibrated";
        case ChainStateOrigin::LearntOnline:
            return "learnt online";
        case ChainStateOrigin::Unresolved:
            return "not in the calibration";
        case ChainStateOrigin::Uncalibrated:
            return "uncalibrated";
    }
    return "?";
}

namespace
{
std::string ns(double s)
{
    std::ostringstream o;
    o.setf(std::ios::fixed | std::ios::showpos);
    o.precision(2);
    o << s * 1e9 << " ns";
    return o.str();
}
}  // namespace

ChainStateTracker::ChainStateTracker(
    unsigned nRx, const PhaseCalibration* cal, ChainStateOptions o, unsigned bandwidthMHz)
    : filters_(nRx), opts_(o), states_(nRx), last_(nRx, kUnknownChainState), changes_(nRx, 0)
{
    if (bandwidthMHz == 0 && cal) bandwidthMHz = cal->chanspec.bandwidthMHz;
    bandwidthMHz_ = bandwidthMHz > 0 ? bandwidthMHz : 80;
    // States and per-frame noise both scale with 1/bandwidth: one set of windows for all.
    const double scale = chainStateDelayScale(bandwidthMHz_);
    opts_.tolerance_s *= scale;
    opts_.measurementSigma_s *= scale;
    opts_.frameTolerance_s *= scale;
    outlierSpan_s_ = 60e-9 * scale;
    calibrated_ = cal != nullptr;
    if (!cal) return;
    calibrationName_ =
        cal->sourcePath.empty() ? cal->device + " " + cal->chanspec.asString() : cal->sourcePath;
    stateAware_ = !cal->chainStates.empty();
    delayOnlyCalibration_ = cal->chainStatesDelayOnly;
    if (stateAware_) opts_.tolerance_s = cal->chainStateTolerance_s;
    for (const auto& st : cal->chainStates)
    {
        if (st.antenna >= nRx) continue;
        ChainStateInfo s;
        s.id = st.state;
        s.delay_s = st.delay_s;
        s.deltaDelay_s = st.deltaDelay_s;
        s.deltaPhase_rad = st.deltaPhase_rad;
        s.origin = ChainStateOrigin::Calibration;
        s.confirmed = true;
        states_[st.antenna].push_back(s);
    }
    for (unsigned i = 0; i < nRx; ++i)
    {
        // The calibration's reference state is the most likely start.
        auto& b = filters_[i].belief;
        b.assign(states_[i].size(), 0.0);
        for (size_t s = 0; s < b.size(); ++s)
            b[s] = states_[i][s].deltaDelay_s == 0 && states_[i][s].deltaPhase_rad == 0 ? 1.0 : 0.1;
    }
}

uint64_t ChainStateTracker::totalChanges() const
{
    uint64_t n = 0;
    for (auto c : changes_) n += c;
    return n;
}

const ChainStateInfo& ChainStateTracker::info(unsigned chain, uint8_t id) const
{
    for (const auto& s : states_.at(chain))
        if (s.id == id) return s;
    throw std::out_of_range(
        "chain " + std::to_string(chain) + " has no state " + std::to_string(id));
}

ChainStateInfo* ChainStateTracker::findState(unsigned chain, uint8_t id)
{
    for (auto& s : states_.at(chain))
        if (s.id == id) return &s;
    return nullptr;
}

const ChainStateInfo* ChainStateTracker::reference(unsigned chain) const
{
    for (const auto& s : states_.at(chain))
        if (s.resolved() && s.deltaDelay_s == 0 && s.deltaPhase_rad == 0) return &s;
    return nullptr;
}

ChainStateInfo& ChainStateTracker::newState(unsigned chain, double delay_s, ChainStateOrigin origin)
{
    auto& list = states_[chain];
    uint8_t id = 0;
    for (const auto& s : list) id = std::max<uint8_t>(id, uint8_t(s.id + 1));
    ChainStateInfo s;
    s.id = std::min<uint8_t>(id, kUnknownChainState - 1);
    s.delay_s = delay_s;
    s.origin = origin;
    s.confirmed = origin == ChainStateOrigin::Assumed;
    if (const ChainStateInfo* ref = reference(chain)) s.deltaDelay_s = delay_s - ref->delay_s;
    list.push_back(s);
    // The filter moves to the new state: the frames that found it were in it.
    auto& b = filters_[chain].belief;
    for (double& v : b) v *= 0.05;
    b.push_back(0.95);
    // A calibration that saw only delay-only states needs none: nothing to warn about.
    if (origin == ChainStateOrigin::Assumed && !delayOnlyCalibration_)
        notices_.push_back(
            "chain " + std::to_string(chain) + ": the calibration '" + calibrationName_ +
            "' holds no jump states; the first state seen (" + ns(delay_s) +
            ") is taken as the one it was made in");
    else if (origin == ChainStateOrigin::Unresolved)
        notices_.push_back(
            "chain " + std::to_string(chain) + ": jump state " + std::to_string(list.back().id) +
            " (" + ns(delay_s) + " relative to chain 0) is not in the calibration '" +
            calibrationName_ +
            "'; learning its phase from the other chains, no bearings from its frames until then");
    return list.back();
}

uint8_t ChainStateTracker::classifyChain(unsigned i, double d, bool valid)
{
    auto& list = states_[i];
    ChainFilter& f = filters_[i];
    if (f.recent.empty())
    {
        f.recent.assign(opts_.discoveryFrames, 0.0);
        f.recentFar.assign(opts_.discoveryFrames, 0);
    }
    // Discovery: a run of frames far from every known state that agree among themselves.
    bool far = valid;
    for (const auto& s : list)
        if (std::abs(d - s.delay_s) <= opts_.tolerance_s) far = false;
    f.recent[f.head] = d;
    f.recentFar[f.head] = far ? 1 : 0;
    f.head = (f.head + 1) % f.recent.size();
    std::vector<double> farDelays;
    for (size_t r = 0; r < f.recent.size(); ++r)
        if (f.recentFar[r]) farDelays.push_back(f.recent[r]);
    // Before the first state: the first frames' median starts it.
    const size_t votes = list.empty() ? opts_.discoveryVotes / 2 : opts_.discoveryVotes;
    if (farDelays.size() >= votes)
    {
        std::nth_element(
            farDelays.begin(), farDelays.begin() + long(farDelays.size() / 2), farDelays.end());
        const double median = farDelays[farDelays.size() / 2];
        size_t agreeing = 0;
        for (double x : farDelays) agreeing += std::abs(x - median) <= opts_.tolerance_s;
        if (agreeing >= votes)
        {
            ChainStateOrigin origin = ChainStateOrigin::Uncalibrated;
            if (calibrated_ && !stateAware_ && !reference(i))
                origin = ChainStateOrigin::Assumed;
            else if (calibrated_ && stateAware_)
                origin = ChainStateOrigin::Unresolved;
            ChainStateInfo& s = newState(i, median, origin);
            s.delaySum_s = median;
            std::fill(f.recentFar.begin(), f.recentFar.end(), 0);
        }
    }
    if (list.empty()) return kUnknownChainState;

    // Forward filter: stay or switch, then weigh by the heavy-tailed likelihood.
    auto& b = f.belief;
    const size_t n = list.size();
    if (n > 1)
    {
        const double q = opts_.switchProbability;
        double total = 0;
        for (double v : b) total += v;
        for (double& v : b) v = (1 - q) * v + q * (total - v) / double(n - 1);
    }
    if (valid)
    {
        // Cauchy core (the per-frame errors are heavy-tailed) plus a uniform floor.
        const double scale = opts_.measurementSigma_s;
        const double tail = opts_.outlierShare / outlierSpan_s_;
        for (size_t s = 0; s < n; ++s)
        {
            const double z = (d - list[s].delay_s) / scale;
            b[s] *= (1 - opts_.outlierShare) / (M_PI * scale * (1 + z * z)) + tail;
        }
    }
    double total = 0;
    for (double v : b) total += v;
    if (!(total > 0)) std::fill(b.begin(), b.end(), 1.0), total = double(n);
    size_t best = 0;
    for (size_t s = 0; s < n; ++s)
    {
        b[s] /= total;
        if (b[s] > b[best]) best = s;
    }
    if (b[best] < opts_.confidence) return kUnknownChainState;
    ChainStateInfo& st = list[best];
    // The filter lags a switch by a few frames: a frame whose own delay disagrees with the
    // state it is given is not trusted with it.
    // (Only on a chain known to jump: with one state there is nothing to confuse it with.)
    if (n > 1 && valid && std::abs(d - st.delay_s) > opts_.frameTolerance_s)
        return kUnknownChainState;
    ++st.frames;
    // States found while running follow their frames; calibrated ones stay as measured.
    if (st.origin != ChainStateOrigin::Calibration && valid &&
        std::abs(d - st.delay_s) <= opts_.tolerance_s)
    {
        st.delay_s += (d - st.delay_s) / double(std::min<uint64_t>(st.frames + 1, 200));
        if (st.origin == ChainStateOrigin::Unresolved)
            if (const ChainStateInfo* ref = reference(i); ref && ref != &st)
                st.deltaDelay_s = st.delay_s - ref->delay_s;
    }
    return st.id;
}

void ChainStateTracker::classify(
    const std::vector<double>& delays_s, const std::vector<double>& coherence,
    std::vector<uint8_t>& ids)
{
    const unsigned n = chains();
    ids.assign(n, 0);
    for (unsigned i = 1; i < n; ++i)
    {
        const double d = i < delays_s.size() ? delays_s[i] : NAN;
        const bool valid =
            std::isfinite(d) && i < coherence.size() && coherence[i] >= opts_.minCoherence;
        ids[i] = classifyChain(i, d, valid);
        if (ids[i] == kUnknownChainState) continue;
        if (last_[i] != kUnknownChainState && last_[i] != ids[i]) ++changes_[i];
        last_[i] = ids[i];
    }
}

bool ChainStateTracker::addLearningEvidence(unsigned chain, uint8_t id, std::complex<double> z)
{
    ChainStateInfo* s = findState(chain, id);
    if (!s || s->origin != ChainStateOrigin::Unresolved || !(std::abs(z) > 0)) return false;
    s->evidence += z / std::abs(z);
    s->evidenceMagnitude += 1.0;
    ++s->evidenceFrames;
    if (s->evidenceFrames < opts_.learnFrames) return false;
    const double coherence = std::abs(s->evidence) / s->evidenceMagnitude;
    if (coherence < opts_.learnCoherence)
    {
        // The evidence disagrees (multipath, a wrong bearing): start over with fresh frames.
        if (s->evidenceFrames >= 4 * opts_.learnFrames)
        {
            s->evidence = {0, 0};
            s->evidenceMagnitude = 0;
            s->evidenceFrames = 0;
        }
        return false;
    }
    s->deltaPhase_rad = std::arg(std::polar(1.0, s->deltaPhase_rad) * s->evidence);
    s->origin = ChainStateOrigin::LearntOnline;
    // Verification starts from the learning frames' evidence; unconfirmed until later blocks
    // agree with it.
    s->verified = std::polar(std::abs(s->evidence), s->deltaPhase_rad);
    s->block = {0, 0};
    s->blockWeight = 0;
    s->blockFrames = 0;
    s->agreeingBlocks = s->disagreeingBlocks = 0;
    s->heldBack = {0, 0};
    s->confirmed = false;
    s->phaseDoubt_rad = opts_.learntPhaseDoubt_rad;
    std::ostringstream o;
    o.precision(2);
    o << std::fixed << "chain " << chain << ": jump state " << int(id) << " (" << ns(s->delay_s)
      << ") learnt online from " << s->evidenceFrames << " frames (coherence " << coherence
      << ", phase " << s->deltaPhase_rad * 180 / M_PI << " deg)" << (s->relearnt ? " again" : "")
      << "; unconfirmed until later frames agree";
    notices_.push_back(o.str());
    return true;
}

bool ChainStateTracker::addVerificationEvidence(
    unsigned chain, uint8_t id, std::complex<double> z, double weight)
{
    ChainStateInfo* s = findState(chain, id);
    if (!opts_.verify || !s || s->origin != ChainStateOrigin::LearntOnline || !(std::abs(z) > 0) ||
        !(weight > 0))
        return false;
    // z is the residual after the current correction: the absolute phase is deltaPhase + arg z.
    s->block += weight * std::polar(1.0, s->deltaPhase_rad) * z / std::abs(z);
    s->blockWeight += weight;
    if (++s->blockFrames < opts_.verifyFrames) return false;
    const double coherence = std::abs(s->block) / s->blockWeight;
    const double disagreement =
        std::abs(std::arg(s->block * std::conj(std::polar(1.0, s->deltaPhase_rad))));
    const std::complex<double> block = s->block;
    s->block = {0, 0};
    s->blockWeight = 0;
    s->blockFrames = 0;
    if (coherence < opts_.learnCoherence) return false;  // inconclusive (multipath, noise)
    std::ostringstream o;
    o.precision(1);
    o << std::fixed << "chain " << chain << ": jump state " << int(id) << " (" << ns(s->delay_s)
      << ")";
    const double before = s->deltaPhase_rad;
    if (disagreement > opts_.disagreement_rad)
    {
        // Held back: one block may be an outlier (frames of another state, a reflection).
        s->agreeingBlocks = 0;
        s->heldBack += block;
        if (!s->confirmed) s->phaseDoubt_rad = std::max(s->phaseDoubt_rad, disagreement);
        if (++s->disagreeingBlocks < opts_.dropBlocks) return false;
        // The learnt phase no longer explains its frames: dropped, learnt again from the
        // blocks that disagree with it; unconfirmed until later ones agree.
        o << ": " << s->disagreeingBlocks << " blocks of later frames disagree with its phase by "
          << disagreement * 180 / M_PI << " deg; dropped and learnt again ("
          << std::arg(s->heldBack) * 180 / M_PI << " deg), unconfirmed";
        notices_.push_back(o.str());
        s->verified = s->heldBack;
        s->heldBack = {0, 0};
        s->deltaPhase_rad = std::arg(s->verified);
        s->disagreeingBlocks = 0;
        s->confirmed = false;
        s->phaseDoubt_rad = opts_.learntPhaseDoubt_rad;
        ++s->relearnt;
        return true;
    }
    s->disagreeingBlocks = 0;
    s->heldBack = {0, 0};
    const bool agrees = disagreement <= opts_.agreement_rad;
    if (agrees) ++s->agreeingBlocks;
    // Every coherent block that does not contradict it refines the phase: each stretch of the
    // drive has its own multipath bias, their sum less of it.
    s->verified += block;
    s->deltaPhase_rad = std::arg(s->verified);
    if (!s->confirmed)
    {
        if (s->agreeingBlocks >= opts_.confirmBlocks)
        {
            s->confirmed = true;
            s->phaseDoubt_rad = 0;
            o << " confirmed by " << s->agreeingBlocks << " blocks of " << opts_.verifyFrames
              << " frames (phase " << s->deltaPhase_rad * 180 / M_PI << " deg)";
            notices_.push_back(o.str());
        }
        else if (agrees)
            s->phaseDoubt_rad = std::max(opts_.agreement_rad, 0.5 * s->phaseDoubt_rad);
        else
            s->phaseDoubt_rad = std::max(s->phaseDoubt_rad, disagreement);
    }
    return s->deltaPhase_rad != before;
}

std::vector<ChainStateCalibration> ChainStateTracker::learntStates(bool confirmedOnly) const
{
    std::vector<ChainStateCalibration> out;
    for (unsigned i = 1; i < chains(); ++i)
        for (const auto& s : states_[i])
        {
            if (s.origin != ChainStateOrigin::LearntOnline || (confirmedOnly && !s.confirmed))
                continue;
            ChainStateCalibration c;
            c.antenna = i;
            c.state = s.id;
            c.delay_s = s.delay_s;
            c.deltaDelay_s = s.deltaDelay_s;
            c.deltaPhase_rad = s.deltaPhase_rad;
            c.frames = s.frames;
            out.push_back(c);
        }
    return out;
}

std::vector<std::string> ChainStateTracker::takeNotices()
{
    std::vector<std::string> out;
    out.swap(notices_);
    return out;
}

std::string ChainStateTracker::summary() const
{
    std::ostringstream o;
    for (unsigned i = 1; i < chains(); ++i)
    {
        o << "  chain " << i << ": " << changes_[i] << " state changes;";
        for (const auto& s : states_[i])
            o << " state " << int(s.id) << " " << ns(s.delay_s) << " " << s.frames << " frames ("
              << toString(s.origin)
              << (s.origin == ChainStateOrigin::LearntOnline
                      ? std::string(s.confirmed ? ", confirmed" : ", unconfirmed")
                      : std::string())
              << (s.relearnt ? ", relearnt " + std::to_string(s.relearnt) + "x" : std::string())
              << ");";
        o << "\n";
    }
    return o.str();
}

}  // namespace mrpt_wifi
