/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/ChainStates.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>

#include <Eigen/Core>
#include <any>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace mrpt_wifi
{
/** The subcarriers a preprocessed frame holds, with their frequencies. Shared by every frame of
 *  one channel, so estimators can key precomputed steering matrices on it. */
struct SubcarrierLayout
{
    Chanspec chanspec;
    std::vector<int> subcarriers;        //!< k, ascending
    std::vector<uint16_t> bins;          //!< k + NFFT/2
    std::vector<double> frequencies_Hz;  //!< f_c + k·312.5 kHz
    double centerFrequency_Hz = 0;
    /** The subcarriers are the observation's own list (CObservationWiFiCSI::subcarrierIndices:
     *  Intel 5300 groups, ESP32 L-LTF / HT-LTF), not the bandwidth's standard data subcarriers;
     *  the Nexmon-specific steps (sub-band sign, firmware-overwritten bins) don't apply. */
    bool sourceListed = false;
    size_t size() const { return subcarriers.size(); }
};

struct PreprocessOptions
{
    /** 80 MHz: multiply k = −128..−65 by −1 (the lowest 20 MHz sub-band arrives negated;
     *  verified on real RT-AC86U captures, DESIGN.md §4). */
    bool correctSubbandSign80 = true;
    /** 40 MHz: multiply k = −64..−1 by −j, as WiROS does. Unverified on hardware: off. */
    bool correctSubbandSign40 = false;
    /** 160 MHz: the 80 MHz correction per 80 MHz segment (k = −256..−193 and 0..63 by −1,
     *  inNegatedSubband()). An extrapolation of the verified 80 MHz quirk, not verified on
     *  hardware (nexmon_csi documents up to 80 MHz); turn off if a real 160 MHz capture shows no
     *  ~180° step at k = −192 / +64. */
    bool correctSubbandSign160 = true;
    /** Leave the subcarriers the firmware overwrites with PHY status (k = +2 at 40/80 MHz) out
     *  of the layout: a frame can't tell whether they were repaired. */
    bool excludeFirmwareOverwritten = true;
    /** Remove the per-packet linear phase across subcarriers (sampling-time offset plus the
     *  mean channel delay), fitted per transmit stream and common to its receive antennas (each
     *  stream has its own cyclic shift delay in 802.11n/ac), centred on k = 0 so the phase
     *  between streams at the centre frequency (the AoD) is kept; then the common phase (CFO).
     *  Delays reported by the estimators are relative to the frame's mean delay. */
    bool removeSamplingTimeOffset = true;
    /** Scale every frame to unit mean power per (stream, antenna, subcarrier) (undoes AGC). */
    bool normalizePower = true;
    /** Frames with a reported RSSI below this are rejected (RSSI 0 = not reported: accepted). */
    double minRssi_dBm = -127;
    /** Without a calibration for the frame's channel: reject the frame (true) or use it
     *  uncalibrated (false). */
    bool requireCalibration = false;
    /** Apply the transmitter's transmit-chain calibration (CalibrationStore::findTransmitter)
     *  when the store has one for the frame's transmitter and channel, after the sampling-time
     *  offset removal (the order in which wifi-calibrate --transmit-chains measured it). */
    bool applyTransmitterCalibration = true;
    /** Use at most this many transmit streams per frame (the first complete ones). */
    unsigned maxStreams = 8;
    /** Accept frames of one receive antenna (a synthetic aperture needs nothing more); false:
     *  rejected as RejectReason::SingleAntenna, since they hold no angle of arrival. */
    bool acceptSingleAntenna = false;
    /** Measure each frame's inter-chain delays and classify the receive chains' jump states
     *  (ChainStates.h); with a calibration, correct each chain for its state before the
     *  calibration, and give no bearing from a frame with a chain in a state the calibration
     *  lacks until its phase is learnt from the other chains. With a calibration that holds no
     *  states (version ≤ 2) or none at all, states are only reported, never applied. */
    bool trackChainStates = true;
    ChainStateOptions chainStates;
};

enum class RejectReason : uint8_t
{
    Accepted = 0,
    LowRssi,
    NoCompleteStream,    //!< no transmit stream arrived on all receive antennas
    ArrayMismatch,       //!< the CSI has more receive chains than the array has elements
    DeadAntenna,         //!< an antenna reported (almost) nothing in every stream
    NoCalibration,       //!< requireCalibration and none for this channel
    UnsupportedChannel,  //!< bandwidth without a data-subcarrier plan
    SingleAntenna,       //!< one receive antenna (e.g. an ESP32): no angle of arrival
    /** Calibrated, but a chain is in a jump state the calibration lacks (phase not learnt
     *  yet) or its state could not be measured in this frame. */
    UnknownChainState,
    /** A receive core the array reads (AntennaArray::coreOf) is not in the frame: a router
     *  reporting only some cores, with an array file that doesn't name them. */
    MissingCore
};
const char* toString(RejectReason r);
constexpr size_t kRejectReasonCount = 10;

/** One CSI frame after preprocessing: the complete streams only, on the layout's subcarriers,
 *  sign-corrected, calibrated, without sampling-time offset, power-normalised. */
struct CleanCsi
{
    mrpt::Clock::time_point timestamp;
    MacAddress transmitter;
    Chanspec chanspec;
    mrpt::poses::CPose3D sensorPose;
    int8_t rssi_dBm = 0;
    uint16_t sequenceNumber = 0;
    uint16_t frameCounter = 0;  //!< the sender's frame counter (firmwareCounter)
    unsigned nRx = 0;
    unsigned nTx = 0;                  //!< streams used
    std::vector<uint8_t> streamIndex;  //!< original transmit stream of each used one
    std::shared_ptr<const SubcarrierLayout> layout;
    /** CSI [(stream·nRx + rx)][subcarrier index of the layout]. */
    Eigen::MatrixXcf H;
    bool calibrated = false;
    /** The transmit-chain calibration applied (nullptr: none; AoD is then not trustworthy). */
    const PhaseCalibration* txCalibration = nullptr;
    double removedSlope_rad = 0;  //!< linear phase removed per subcarrier step (first stream)
    double removedDelay_s = 0;    //!< the same as a delay: −slope / (2π·312.5 kHz)
    /** Per receive chain: delay relative to chain 0 [s] and jump state id (empty when
     *  PreprocessOptions::trackChainStates is off; kUnknownChainState: not measurable). */
    std::vector<double> chainDelay_s;
    std::vector<uint8_t> chainState;
    /** How far [rad] this frame's bearing may be off because a chain is in a learnt jump state
     *  not yet confirmed (ChainStateInfo::phaseDoubt_rad turned into the bearing shift it would
     *  cause); 0 when every state is calibrated or confirmed. Bearing σ covers it. */
    double stateDoubt_rad = 0;

    /** Spatial covariance over streams and subcarriers, split into `groups` contiguous
     *  sub-bands (so each can use its own centre frequency): group g is
     *  Σ_{m, k∈g} h_{m,k} h_{m,k}^H (nRx × nRx). Computed once per frame and group count. */
    const std::vector<Eigen::MatrixXcd>& groupCovariances(unsigned groups) const;
    /** Same over receive antennas and subcarriers, across transmit streams (nTx × nTx): the
     *  transmitter-side covariance used for the angle of departure. */
    const std::vector<Eigen::MatrixXcd>& txGroupCovariances(unsigned groups) const;

    /** Forgets the cached covariances and derived() terms (after changing H by hand). */
    void invalidateCaches() const;

    /** A statistic an estimator derives from this frame alone (e.g. its terms of a windowed
     *  angle × delay profile), computed once per frame like the covariances: an estimate over
     *  a sliding window then computes it only for the window's new frame and sums the rest.
     *  `owner` names the computation and its configuration (newDerivedOwner(); a new one
     *  whenever the configuration changes); `compute(M&)` fills the value on a miss, reusing
     *  the storage of the slot's previous frame. Frames that never went through
     *  CsiPreprocessor::process() or invalidateCaches() are not cached (computed on every
     *  call). The reference is valid until the next derived() call on this frame. Not
     *  thread-safe, like the covariances. */
    template <typename M, typename Compute>
    const M& derived(uint64_t owner, Compute&& compute) const
    {
        Derived* d = nullptr;
        for (auto& e : derived_)
            if (e.owner == owner) d = &e;
        if (!d)
        {
            if (derived_.size() >= kMaxDerived) derived_.erase(derived_.begin());
            derived_.reserve(kMaxDerived);
            d = &derived_.emplace_back();
            d->owner = owner;
        }
        if (!std::any_cast<M>(&d->value)) d->value = M();
        M& value = *std::any_cast<M>(&d->value);
        if (contentId_ == 0 || d->contentId != contentId_)
        {
            compute(value);
            d->contentId = contentId_;
        }
        return value;
    }
    /** A process-wide unique `owner` for derived(). */
    static uint64_t newDerivedOwner();

    /** Which layout indices each of `groups` sub-bands covers: [begin, end). */
    static std::pair<size_t, size_t> groupRange(size_t nSub, unsigned groups, unsigned g);

private:
    mutable unsigned covGroups_ = 0, txCovGroups_ = 0;
    mutable std::vector<Eigen::MatrixXcd> cov_, txCov_;
    struct Derived
    {
        uint64_t owner = 0, contentId = 0;
        std::any value;
    };
    static constexpr size_t kMaxDerived = 4;  //!< computations cached per frame
    /** Identifies H's current content (0: a frame built by hand, not cached). */
    mutable uint64_t contentId_ = 0;
    mutable std::vector<Derived> derived_;
    friend class CsiPreprocessor;
};

/** Turns CObservationWiFiCSI into CleanCsi (see PreprocessOptions for the steps, in order:
 *  RSSI gate, stream selection, sign correction, calibration, sampling-time offset, masked-bin
 *  repair, power normalisation). Keeps per-channel caches; not thread-safe. */
class CsiPreprocessor
{
public:
    CsiPreprocessor() = default;
    CsiPreprocessor(PreprocessOptions options, AntennaArray rxArray, CalibrationStore calib = {});

    const PreprocessOptions& options() const { return options_; }
    const AntennaArray& rxArray() const { return rxArray_; }
    const CalibrationStore& calibration() const { return calib_; }

    /** Fills `out` (reusing its storage). Throws CalibrationError when a calibration exists for
     *  the channel but does not fit (another device, too few antennas). */
    RejectReason process(const CObservationWiFiCSI& in, CleanCsi& out);

    /** The layout of a channel's standard data subcarriers. Throws std::invalid_argument for a
     *  bandwidth without a data-subcarrier plan. */
    std::shared_ptr<const SubcarrierLayout> layoutFor(const Chanspec& cs);
    /** The layout a frame is processed on (cached, shared by every frame with the same channel
     *  and subcarrier list): the observation's own subcarrier list when it has one (grouped /
     *  sparse sources), else the standard one. Throws std::invalid_argument for a list with
     *  indices outside the bandwidth or not strictly ascending. */
    std::shared_ptr<const SubcarrierLayout> layoutFor(const CObservationWiFiCSI& in);

    /** Checks before any processing that the array and the calibration fit a frame of this
     *  shape (channel, receive chains, their cores); throws CalibrationError /
     *  std::invalid_argument with a clear message. */
    void checkCompatible(
        const Chanspec& cs, unsigned nRx, const std::vector<uint8_t>& rxCores = {});

    /** The CSI row each array element reads in a frame (element i: the row of core
     *  rxArray().coreOf(i)); all elements when the array names its cores, else one per row of
     *  the frame. Returns ArrayMismatch or MissingCore when the frame doesn't fit. */
    RejectReason elementRows(const CObservationWiFiCSI& in, std::vector<unsigned>& rows) const;
    /** Why a frame's receive cores don't fit the array, with what to do; empty if they fit. */
    std::string coreMismatchMessage(const CObservationWiFiCSI& in) const;

    /** Per-packet phase slope across subcarriers [rad per subcarrier index], from the products
     *  of neighbouring subcarriers summed over the given rows (robust: no unwrapping). Sparse
     *  layouts (e.g. Intel's groups of 2 or 4): the most common spacing gives the slope modulo
     *  2π/spacing, the other spacings refine it by least squares on their phase differences.
     *  Unambiguous up to π/spacing rad per subcarrier (400 ns of delay at spacing 4). Exposed
     *  for tests. */
    static double estimatePhaseSlope(
        const Eigen::Ref<const Eigen::MatrixXcf>& H, const std::vector<int>& k);

    /** The jump-state trackers, one per (channel, receive chain count) seen so far. */
    std::vector<const ChainStateTracker*> chainStateTrackers() const;
    /** Notices of every tracker (a state the calibration lacks, a state learnt), taken once. */
    std::vector<std::string> takeChainStateNotices();
    /** State changes seen, summed over channels and chains. */
    uint64_t chainStateChanges() const;
    /** Per channel whose state-aware calibration got learnt states (confirmed ones only, by
     *  default): a copy of the calibration with them added, so the next run knows them. */
    std::vector<PhaseCalibration> calibrationsWithLearntStates(bool confirmedOnly = true) const;

private:
    struct ChannelCache
    {
        ChainStateTracker states;
        std::shared_ptr<const SubcarrierLayout> layout;
        const PhaseCalibration* calibration = nullptr;
        Eigen::MatrixXcf calibrationFactors;  //!< [rx][subcarrier]: e^{−jφ}·10^{−g/20}
        Eigen::VectorXf sign;                 //!< sub-band correction (real parts)
        Eigen::VectorXf signImag;             //!< imaginary part (the 40 MHz −j case)
        bool hasSignCorrection = false;
    };
    ChannelCache& cacheFor(const std::shared_ptr<const SubcarrierLayout>& layout, unsigned nRx);
    /** One frame's evidence for the phase of chain `chain`'s Unresolved state: the bearing from
     *  the other (calibrated) chains, then the chain's residual phase against it. */
    void learnChainState(ChannelCache& cache, const CleanCsi& f, unsigned chain);
    /** Checks the frame's learnt states against the other chains (verification evidence) and
     *  sets f.stateDoubt_rad for those not confirmed yet. */
    void verifyChainStates(ChannelCache& cache, CleanCsi& f);
    std::vector<double> chainCoherence_;  //!< scratch
    std::vector<unsigned> rows_;          //!< scratch: CSI row of each array element
    struct TransmitterCache
    {
        const PhaseCalibration* calibration = nullptr;
        Eigen::MatrixXcf factors;  //!< [transmit chain][subcarrier]: e^{−jψ}·10^{−g/20}
    };
    const TransmitterCache& transmitterCacheFor(
        const MacAddress& mac, const SubcarrierLayout& layout, unsigned streams);
    std::map<std::pair<MacAddress, uint32_t>, TransmitterCache> txCaches_;

    PreprocessOptions options_;
    AntennaArray rxArray_;
    CalibrationStore calib_;
    std::map<std::pair<const SubcarrierLayout*, unsigned>, ChannelCache> caches_;
    /** Layouts by (centre channel << 16 | bandwidth, the observation's subcarrier list). */
    std::map<std::pair<uint32_t, std::vector<int16_t>>, std::shared_ptr<const SubcarrierLayout>>
        layouts_;
    std::pair<uint32_t, std::vector<int16_t>> lastLayoutKey_;  //!< of lastLayout_
    std::shared_ptr<const SubcarrierLayout> lastLayout_;
};

/** The recent frames of one transmitter: a ring of CleanCsi, storage reused. Frames of another
 *  shape (channel, antennas, streams) than the ones held flush it. */
class CsiWindow
{
public:
    explicit CsiWindow(size_t capacity = 16, double maxAge_s = 1.0);

    /** The slot the next frame goes into (oldest one when full): fill it, then commit(). */
    CleanCsi& slot();
    void commit();

    size_t size() const { return count_; }
    size_t capacity() const { return ring_.size(); }
    /** Up to n most recent frames that are at most maxAge (or `maxAge_s`, if given and
     *  shorter) older than the newest, oldest first. */
    void recent(
        size_t n, std::vector<const CleanCsi*>& out,
        std::optional<double> maxAge_s = std::nullopt) const;
    const CleanCsi& newest() const;
    void clear() { count_ = 0; }

private:
    std::vector<CleanCsi> ring_;
    size_t head_ = 0;  //!< index of the next slot
    size_t count_ = 0;
    double maxAge_s_;
};

/** One CsiWindow per transmitter MAC. */
class TransmitterWindows
{
public:
    TransmitterWindows(size_t capacity = 16, double maxAge_s = 1.0)
        : capacity_(capacity), maxAge_s_(maxAge_s)
    {
    }
    CsiWindow& of(const MacAddress& mac);
    size_t size() const { return windows_.size(); }

private:
    size_t capacity_;
    double maxAge_s_;
    std::unordered_map<MacAddress, CsiWindow> windows_;
};

}  // namespace mrpt_wifi
