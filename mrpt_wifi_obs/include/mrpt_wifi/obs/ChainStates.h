/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/PhaseCalibration.h>

#include <Eigen/Core>
#include <cmath>
#include <complex>
#include <cstdint>
#include <string>
#include <vector>

/** The receive chains' jump states.
 *
 * The BCM4366c0 (RT-AC86U) switches the delay between its receive chains among a few values,
 * each state with its own phase. The steps are about a quarter of the sample period: ~3 ns at
 * 80 MHz (nexmon_csi issues #82, #219, #348, #393), ~12.5 ns at 20 MHz (one 80 MHz sample;
 * measured on the muTrack splitter captures: states −21, −9, +4, +16 ns). A step turns the phase
 * across the band by ~1.5 rad from band edge to band edge at any bandwidth, while a path's delay
 * difference across a 7.8 cm array is below 0.26 ns: so each frame's inter-chain delay tells
 * its state, and a calibration per state removes the jump. The per-frame delay noise scales
 * the same way (1/bandwidth), so every delay window here is given for 80 MHz and scaled by
 * 80/bandwidth (chainStateDelayScale). */
namespace mrpt_wifi
{
class CObservationWiFiCSI;
struct SubcarrierLayout;

/** A chain whose state a frame could not tell (too little coherent energy). */
constexpr uint8_t kUnknownChainState = 255;

/** How much wider the jump states and the delay windows are at `bandwidthMHz` than at 80 MHz:
 *  80 / bandwidth (4 at 20 MHz); 1 for 0 (unknown). */
double chainStateDelayScale(unsigned bandwidthMHz);
/** The bandwidth [MHz] a list of subcarriers k spans: 20, 40, 80 or 160 (by the largest |k|). */
unsigned bandwidthOfSubcarriers(const std::vector<int>& k);

/** Per-frame delay of each receive chain relative to chain 0, from the cross spectrum
 *  z_k = Σ_m h_{m,i}(k)·h_{m,0}(k)^* over the subcarriers k (common sampling-time offset and
 *  phase cancel; chain 0 is 0). `coherence[i]` ∈ [0, 1]: how consistently neighbouring
 *  subcarriers agree on the phase progression (low: noise or a dead chain). Strong signals
 *  (coherence ≥ 0.97, about 20 dB and up) take the phase slope of neighbouring subcarriers,
 *  which stays with the main path under multipath; weaker ones the delay profile
 *  |Σ_k z_k·e^{j2π·Δf·k·τ}| (within ±25 ns), where all subcarriers add coherently: at 10 dB the
 *  slope strays by 1.6 ns (median; p90 9 ns), the profile by 0.6 ns (p90 1.7 ns; development
 *  rooms, 80 MHz). The windows scale with 80/bandwidth (±100 ns at 20 MHz), the bandwidth told
 *  by the subcarriers. H rows are stream·nRx + rx, columns the subcarriers `k` (ascending). */
void measureChainDelays(
    const Eigen::Ref<const Eigen::MatrixXcf>& H, unsigned nRx, const std::vector<int>& k,
    std::vector<double>& delays_s, std::vector<double>& coherence);

/** The same on a raw observation: its complete streams on the layout's subcarriers (masked
 *  bins left out). False if the frame has fewer than two chains or no complete stream. */
bool measureChainDelays(
    const CObservationWiFiCSI& obs, const SubcarrierLayout& layout, std::vector<double>& delays_s,
    std::vector<double>& coherence);

/** Where a state's correction comes from. */
enum class ChainStateOrigin : uint8_t
{
    Calibration,   //!< the calibration file lists it
    Assumed,       //!< a state-unaware calibration: the first state seen is taken as its own
    LearntOnline,  //!< its phase was learnt from the other chains while running
    Unresolved,    //!< not in the calibration, phase not learnt yet: no bearing from it
    Uncalibrated   //!< there is no calibration: the state is only reported
};
const char* toString(ChainStateOrigin o);

/** One jump state of one chain, as the tracker knows it. */
struct ChainStateInfo
{
    uint8_t id = 0;
    double delay_s = 0;         //!< centre of the measured delays relative to chain 0
    double deltaDelay_s = 0;    //!< relative to the chain's reference state
    double deltaPhase_rad = 0;  //!< relative to the chain's reference state
    uint64_t frames = 0;        //!< frames classified into it while running
    ChainStateOrigin origin = ChainStateOrigin::Uncalibrated;
    /** Whether a frame in it can be corrected (reference, calibrated or learnt). */
    bool resolved() const
    {
        return origin == ChainStateOrigin::Calibration || origin == ChainStateOrigin::Assumed ||
               origin == ChainStateOrigin::LearntOnline;
    }

    // Online learning of an Unresolved state: Σ of per-frame phase evidence and its |·|.
    std::complex<double> evidence{0, 0};
    double evidenceMagnitude = 0;
    size_t evidenceFrames = 0;
    double delaySum_s = 0;  //!< running centre of states found while running

    // Verification of a LearntOnline state against the other chains, after learning.
    /** Enough blocks of later frames agreed with its phase; calibrated states always are. */
    bool confirmed = false;
    /** Σ of every frame's phase evidence since learning, as absolute phasors e^{j·phase}: its
     *  angle is the state's phase, refined as the robot moves (multipath bias averages out). */
    std::complex<double> verified{0, 0};
    std::complex<double> block{0, 0};  //!< the current block's absolute phasors
    double blockWeight = 0;
    std::complex<double> heldBack{0, 0};  //!< disagreeing blocks in a row, not merged yet
    size_t blockFrames = 0;
    unsigned agreeingBlocks = 0, disagreeingBlocks = 0;
    unsigned relearnt = 0;  //!< times dropped and learnt again
    /** While unconfirmed: how far its phase may be off [rad] (0 once confirmed). */
    double phaseDoubt_rad = 0;
};

/** How frames are classified. One frame's inter-chain delay is a noisy witness of its state:
 *  multipath moves it by ~0.6 ns (median) and, in one frame of ten, by 1.7 ns or more (random
 *  rooms, 80 MHz, 10–25 dB). The states persist for seconds, so each chain runs a hidden-Markov
 * forward filter over its states with a heavy-tailed likelihood, and a frame gets a state only when
 *  the filter is confident; otherwise it is "unknown" (no bearing from it when a state-aware
 *  calibration is in use). The delays below are for 80 MHz: the tracker multiplies them by
 *  chainStateDelayScale(bandwidth) (×4 at 20 MHz, where states are ~12.5 ns apart). */
struct ChainStateOptions
{
    /** A delay farther than this from every known state counts towards a new state (the jumps
     *  are ~3 ns apart at 80 MHz); also the matching tolerance of calibration files made with
     *  it. */
    double tolerance_s = 1.5e-9;
    double measurementSigma_s = 0.7e-9;  //!< Cauchy scale of the per-frame likelihood
    double outlierShare = 0.1;           //!< its uniform floor (over ±30 ns)
    double switchProbability = 1e-4;     //!< per frame, of leaving the current state
    double confidence = 0.99;            //!< posterior a frame needs to get a state
    /** ... and its own delay within this of that state's (else it is "unknown"; the states are
     *  ~3 ns apart, so a frame of a neighbouring state the filter has not caught up with is
     *  still refused). */
    double frameTolerance_s = 2.0e-9;
    /** A new state is found when `discoveryVotes` of the last `discoveryFrames` frames lie far
     *  from every known state and agree among themselves within the tolerance. */
    size_t discoveryFrames = 24, discoveryVotes = 20;
    /** A chain whose delay is measured with less coherence than this gives no evidence in that
     *  frame. */
    double minCoherence = 0.2;
    /** Online learning: frames of evidence, and the coherence of their phases, before an
     *  Unresolved state is taken as learnt. */
    size_t learnFrames = 30;
    double learnCoherence = 0.7;
    /** Verification of a learnt state: its later frames, in blocks of `verifyFrames`, keep
     *  measuring its phase against the other chains. A coherent block within `agreement_rad`
     *  of the state's phase agrees and refines it; `confirmBlocks` agreeing blocks confirm
     *  it. A coherent block farther than `disagreement_rad` is held back; `dropBlocks` of them
     *  in a row drop the learnt phase, which is learnt again from those blocks. Until
     *  confirmed, its frames carry a phase doubt: `learntPhaseDoubt_rad` when (re)learnt (30
     *  frames of a multipath-biased reference can be off by that much), halved by each
     *  agreeing block down to `agreement_rad`, raised to any larger disagreement seen. */
    bool verify = true;  //!< false: a learnt state is trusted as learnt (before issue 53)
    size_t verifyFrames = 60;
    double agreement_rad = 15 * M_PI / 180;
    double disagreement_rad = 45 * M_PI / 180;
    unsigned confirmBlocks = 5, dropBlocks = 2;
    double learntPhaseDoubt_rad = M_PI / 2;
};

/** The jump states of one receiver on one channel: classifies each frame's chain delays, counts
 *  state changes, holds each state's correction (from a calibration, or learnt while running),
 *  and collects notices for the user. Deterministic: the same frames in the same order give the
 *  same states live and offline. Not thread-safe. */
class ChainStateTracker
{
public:
    ChainStateTracker() = default;
    /** nRx chains; `cal` (may be null) seeds the states it knows; `bandwidthMHz` scales the
     *  options' delay windows (chainStateDelayScale). 0: the calibration's bandwidth, or the
     *  options as given (80 MHz) without a calibration. */
    ChainStateTracker(
        unsigned nRx, const PhaseCalibration* cal, ChainStateOptions o = {},
        unsigned bandwidthMHz = 0);

    unsigned chains() const { return unsigned(states_.size()); }
    /** The options in use: delay windows scaled to the bandwidth. */
    const ChainStateOptions& options() const { return opts_; }
    /** The bandwidth the delay windows are scaled for [MHz]. */
    unsigned bandwidthMHz() const { return bandwidthMHz_; }
    /** A calibration is in use. */
    bool calibrated() const { return calibrated_; }
    /** The calibration knows its states: corrections are applied, and frames whose state is
     *  unknown or unresolved give no bearing. Otherwise states are only reported. */
    bool applies() const { return calibrated_ && stateAware_; }
    /** The calibration's recording showed states that differ by a delay alone (none listed,
     *  none needed). */
    bool delayOnlyCalibration() const { return delayOnlyCalibration_; }

    /** The state id of every chain for one frame's measured delays (chain 0: 0). A chain
     *  measured with too little coherence gets kUnknownChainState; a delay that fits no known
     *  state starts a new one (Unresolved with a calibration, Uncalibrated without). */
    void classify(
        const std::vector<double>& delays_s, const std::vector<double>& coherence,
        std::vector<uint8_t>& ids);

    const ChainStateInfo& info(unsigned chain, uint8_t id) const;
    const std::vector<ChainStateInfo>& states(unsigned chain) const { return states_.at(chain); }
    /** State changes seen on a chain (a frame in another state than the chain's previous one). */
    uint64_t changes(unsigned chain) const { return changes_.at(chain); }
    uint64_t totalChanges() const;

    /** Adds one frame's evidence for the phase of an Unresolved state: z = Σ over streams and
     *  subcarriers of (chain's calibrated CSI)·conj(the other chains' steered sum). When enough
     *  frames agree the state becomes LearntOnline with deltaPhase = −arg(Σ z) relative to its
     *  current correction. Returns true when this frame completed the learning. */
    bool addLearningEvidence(unsigned chain, uint8_t id, std::complex<double> z);

    /** Adds one frame's evidence (as for addLearningEvidence, `weight` ∈ [0, 1]) for a
     *  LearntOnline state's phase after learning: refines its phase with every block, confirms
     *  it or drops it to be learnt again (ChainStateOptions::verifyFrames). Returns true when
     *  the state's correction changed. Other states ignore it. */
    bool addVerificationEvidence(
        unsigned chain, uint8_t id, std::complex<double> z, double weight = 1.0);

    /** The learnt states, as calibration entries (relative to each chain's reference state,
     *  with the tracker's tolerance): what a calibration file can hold so the next run knows
     *  them. `confirmedOnly`: only the confirmed ones. */
    std::vector<ChainStateCalibration> learntStates(bool confirmedOnly = true) const;

    /** Messages for the user (a state the calibration lacks, a state learnt), taken once. */
    std::vector<std::string> takeNotices();
    /** One line per chain: its states (delay, frames, origin) and changes. */
    std::string summary() const;

private:
    ChainStateInfo& newState(unsigned chain, double delay_s, ChainStateOrigin origin);
    /** Chain's state `id`, or null. */
    ChainStateInfo* findState(unsigned chain, uint8_t id);
    const ChainStateInfo* reference(unsigned chain) const;
    /** One chain's forward-filter step; returns its state id or kUnknownChainState. */
    uint8_t classifyChain(unsigned chain, double delay_s, bool valid);

    struct ChainFilter
    {
        std::vector<double> belief;  //!< parallel to states_[chain]
        std::vector<double> recent;  //!< last delays far from every state (ring)
        std::vector<uint8_t> recentFar;
        size_t head = 0;
    };
    std::vector<ChainFilter> filters_;

    ChainStateOptions opts_;
    unsigned bandwidthMHz_ = 80;
    double outlierSpan_s_ = 60e-9;  //!< width of the likelihood's uniform floor
    bool calibrated_ = false, stateAware_ = false;
    std::string calibrationName_;
    bool delayOnlyCalibration_ = false;  //!< its recording's states differed by a delay alone
    std::vector<std::vector<ChainStateInfo>> states_;  //!< [chain]
    std::vector<uint8_t> last_;                        //!< previous state per chain
    std::vector<uint64_t> changes_;
    std::vector<std::string> notices_;
};

}  // namespace mrpt_wifi
