/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>

#include <Eigen/Core>
#include <map>
#include <memory>
#include <string>
#include <vector>

/** Phase calibration of a receive array (the paper's "Quick and easy calibration"). */
namespace mrpt_wifi::calib
{
/** One CSI frame ready for calibration: sign-corrected, without sampling-time offset and common
 *  phase, power-normalised, *uncalibrated*, with the bearing it should have had. */
struct CalibrationFrame
{
    double time_s = 0;  //!< UNIX seconds
    MacAddress transmitter;
    Chanspec chanspec;
    int8_t rssi_dBm = 0;
    unsigned nRx = 0;
    unsigned nTx = 0;  //!< streams used
    std::shared_ptr<const SubcarrierLayout> layout;
    Eigen::MatrixXcf H;  //!< [(stream·nRx + rx)][subcarrier of the layout]

    bool hasGeometry = false;        //!< false in splitter mode: every antenna sees the same signal
    double expectedAoa_rad = 0;      //!< line-of-sight direction of the transmitter, sensor frame
    double distance_m = 0;           //!< receive array to transmitter
    mrpt::math::TPose2D sensorPose;  //!< receive array in the transmitter's frame

    /** Per receive chain: delay relative to chain 0 [s] and jump state id as the preparer's
     *  tracker classified it (empty: not tracked; kUnknownChainState: not measurable). */
    std::vector<double> chainDelay_s;
    std::vector<uint8_t> chainState;
};

/** Undoes each chain's jump state as a calibration holds it (the state matched by the frame's
 *  measured delay): H of chain i is multiplied by e^{+j2πkΔf·Δd}·e^{−jΔψ}. False (frame left
 *  as it was or partly corrected) if a chain's delay matches no state of the calibration; true
 *  without change for a state-unaware calibration. */
bool removeChainStates(const PhaseCalibration& c, CalibrationFrame& f);

/** Whether a calibration file should list its jump states (wifi-calibrate --chain-states). */
enum class ChainStatePolicy : uint8_t
{
    Auto,    //!< unless every state differs from its reference by a delay alone
    Always,  //!< whenever the recording showed states
    Never    //!< a state-unaware file
};
/** Two states of a chain whose phases at the centre frequency agree within this have the same
 *  offsets (the muTrack RT-AC86Us' states agree within 0.4°). */
constexpr double kSameStatePhase_rad = 3 * M_PI / 180;

/** Parses "auto|on|off"; throws std::invalid_argument naming `what` otherwise. */
ChainStatePolicy chainStatePolicyFromString(const std::string& s, const std::string& what);

/** Applies the policy to a calibration about to be written: with Auto, a table whose every
 *  state's phase at the centre frequency equals its reference's within `maxPhase_rad` is
 *  dropped. Such states are sample slips in the chain's digital front end (the muTrack
 *  RT-AC86Us: 12.5 ns apart at 20 MHz, phases within 0.4°): the phases hold in every state,
 *  and over the air a frame's inter-chain delay carries a multipath bias of several ns (tens at
 *  20 MHz), so it can't be matched to a state measured through cables — a state-aware file
 *  would withhold bearings from those frames until each state is learnt again. Returns what
 *  was done, for the user (empty: nothing). */
std::string applyChainStatePolicy(
    PhaseCalibration& c, ChainStatePolicy policy, double maxPhase_rad = kSameStatePhase_rad);

/** Preprocessing used for calibration: sub-band sign correction, STO/CFO removal and power
 *  normalisation on; no calibration applied; the firmware-overwritten subcarrier left out. */
PreprocessOptions calibrationPreprocessOptions();

/** Turns CObservationWiFiCSI into CalibrationFrame (one instance per thread). */
class FramePreparer
{
public:
    explicit FramePreparer(
        AntennaArray array, PreprocessOptions opts = calibrationPreprocessOptions());

    const AntennaArray& array() const { return pre_.rxArray(); }

    /** Drive mode: the robot base pose and the transmitter position in one frame; the receive
     *  array sits at obs.sensorPose on the robot. */
    RejectReason prepare(
        const CObservationWiFiCSI& obs, const mrpt::math::TPose2D& robotPose,
        const mrpt::math::TPoint2D& transmitter, CalibrationFrame& out);
    /** Splitter mode: no geometry. */
    RejectReason prepareStatic(const CObservationWiFiCSI& obs, CalibrationFrame& out);

    /** The jump states seen so far (one tracker per channel and chain count). */
    std::vector<const ChainStateTracker*> chainStateTrackers() const;

private:
    RejectReason common(const CObservationWiFiCSI& obs, CalibrationFrame& out);
    CsiPreprocessor pre_;
    CleanCsi clean_;
    // The jump states are classified here, on the preprocessed CSI of the array's elements,
    // by a tracker that knows the channel's bandwidth (the states and their windows scale
    // with it: chainStateDelayScale).
    bool trackStates_ = false;
    ChainStateOptions stateOptions_;
    std::map<std::pair<uint32_t, unsigned>, ChainStateTracker> trackers_;
    std::vector<double> coherence_;
};

enum class CalibrationMode : uint8_t
{
    Drive,    //!< robot drives near a transmitter at a known position (expected bearings)
    Splitter  //!< one transmitter fed through a splitter and equal cables to every antenna
};

struct CalibratorOptions
{
    CalibrationMode mode = CalibrationMode::Drive;
    /** Frames are pooled into segments of this duration: the unit the robust loss weighs (a
     *  reflection that dominates for a moment spoils one segment, not the fit). */
    double segment_s = 0.5;
    /** Cauchy scale of the robust loss, on the normalised misfit of one segment at one
     *  subcarrier (0: plain least squares). */
    double robustScale = 0.3;
    unsigned maxIterations = 50;
    /** Estimate per-antenna gains (mean power ratio to antenna 0) too. */
    bool estimateGains = true;
    /** Frames kept (evenly spread) to measure bearing errors before/after and for reports. */
    size_t checkFrames = 1500;

    // What makes a drive able to determine a calibration (warnings otherwise).
    size_t minFrames = 300;
    double minDuration_s = 15;    //!< drive mode only
    double bearingBin_deg = 10;   //!< histogram of expected bearings ...
    unsigned minBearingBins = 6;  //!< ... needs this many bins with ≥ minBinShare of frames
    double minBinShare = 0.005;
    double maxMedianDistance_m = 8;  //!< the paper drives within 5 m
    double losCoherence = 0.8;       //!< a segment is LoS-dominated if the fit explains this
    double minLosShare = 0.5;        //!< share of frames in LoS-dominated segments
    /** Drive mode: warn when the calibration leaves this 90th-percentile bearing error on the
     *  drive's own frames (it does not explain the drive). */
    double maxP90Error_deg = 20;
    /** A jump state needs at least this many frames (and this share of the drive) to be
     *  calibrated; frames in rarer states are left out. */
    size_t minStateFrames = 50;
    double minStateShare = 0.02;
};

/** One jump state of one chain as the calibration drive saw it. */
struct ChainStateDiagnostics
{
    unsigned antenna = 1;
    uint8_t state = 0;
    size_t frames = 0;
    double delay_s = 0, deltaDelay_s = 0, deltaPhase_rad = 0;
    bool reference = false;  //!< the chain's most visited state (phases_rad hold in it)
};

/** What the fit found out about the data (numbers for stdout and the report). */
struct CalibrationDiagnostics
{
    std::vector<ChainStateDiagnostics> chainStates;  //!< every state of every chain ≥ 1
    uint64_t chainStateChanges = 0;
    size_t unknownStateFrames = 0;  //!< frames left out: a chain's state not measurable
    /** States within the tracker's tolerance of their chain's reference in delay and with its
     *  phase: the reference seen through multipath, merged into it. */
    size_t mergedChainStates = 0;
    size_t frames = 0, snapshots = 0, segments = 0;
    double duration_s = 0;
    unsigned bearingBins = 0;    //!< occupied bins of the expected-bearing histogram
    double bearingSpan_deg = 0;  //!< 5–95 % range of the expected bearings (folded)
    double medianDistance_m = 0;
    double losShare = 0;        //!< frames in segments the calibrated LoS explains well
    double principalShare = 0;  //!< mean λ0 / tr(R) of the pooled per-subcarrier covariances
    double residual_rad = 0;    //!< RMS phase residual: sqrt(−ln coherence) after the fit
    double coarseResidual_rad = 0;
    unsigned iterations = 0;
    double initialCost = 0, finalCost = 0;
    double solveTime_s = 0;
    std::string solverReport;
};

/** The outcome of calibrating one channel. */
struct ChannelCalibration
{
    PhaseCalibration calibration;                       //!< to be saved (antenna 0 ≡ 0)
    std::vector<std::vector<double>> coarsePhases_rad;  //!< principal component, [ant][sub]
    CalibrationDiagnostics diag;
    /** Bearing errors [deg] on the kept frames, without and with the calibration (drive mode). */
    std::vector<double> bearingErrorBefore_deg, bearingErrorAfter_deg;
    std::vector<std::string> warnings;  //!< why the drive may not determine a calibration
    bool determined() const { return warnings.empty(); }
};

/** Accumulates frames (per channel) and solves for the calibration.
 *
 * Drive mode, per frame t and subcarrier k: the CSI h_tk (one vector over antennas per stream)
 * is suppressed by the expected steering, x_tk = h_tk ⊙ conj(a(θ_t, f_k)), leaving
 * c_tk · e^{jΦ_k} + multipath + noise with c_tk a common complex factor (LoS gain, the per-packet
 * delay and phase). Because c_tk changes per packet and subcarrier, the principal component is
 * taken per subcarrier (R_k = Σ x x^H, invariant to c_tk) rather than of the flattened matrix
 * as in the paper. Φ_k^coarse = ∠u0(R_k) relative to antenna 0; then Levenberg–Marquardt
 * (Ceres) refines the unit-modulus e^{jΦ_k} against the orthogonal subspace of each segment's
 * R_sk, weighted by the eigen-gaps (exactly the power the calibrated LoS leaves unexplained),
 * with a Cauchy loss per segment × subcarrier. Splitter mode: the same without suppression.
 * Memory: O(segments × subcarriers × antennas²), frames are not kept (except checkFrames). */
class PhaseCalibrator
{
public:
    explicit PhaseCalibrator(AntennaArray array, CalibratorOptions opts = {});

    const CalibratorOptions& options() const { return opts_; }
    const AntennaArray& array() const { return array_; }

    /** Adds a frame (frames of one channel in time order). Throws std::invalid_argument for a
     *  frame without geometry in drive mode or with more antennas than the array. */
    void add(const CalibrationFrame& f);

    std::vector<Chanspec> channels() const;
    size_t frames(const Chanspec& cs) const;

    /** Calibrates one channel; `device` defaults to the array name. Throws std::runtime_error
     *  if there are no frames for it. */
    ChannelCalibration solve(const Chanspec& cs) const;

private:
    struct Segment
    {
        double t0 = 0;
        size_t frames = 0;
        std::vector<Eigen::MatrixXcd> R;  //!< [subcarrier] Σ x x^H
        MacAddress transmitter;           //!< one transmitter's frames (one geometry) per segment
        std::vector<uint8_t> chainState;  //!< one jump state per chain per segment
    };
    struct StateStats
    {
        size_t frames = 0;
        double delaySum_s = 0;
    };
    struct Channel
    {
        std::shared_ptr<const SubcarrierLayout> layout;
        unsigned nRx = 0;
        std::vector<Segment> segments;
        std::map<MacAddress, size_t> openSegment;  //!< per transmitter: index into segments
        Eigen::VectorXd antennaPower;
        size_t frames = 0, snapshots = 0;
        double tFirst = 0, tLast = 0;
        std::vector<float> foldedAoa, distance;
        std::vector<CalibrationFrame> kept;
        size_t keepStride = 1, seen = 0;
        std::map<std::pair<unsigned, uint8_t>, StateStats> states;  //!< (chain, state)
        size_t unknownStateFrames = 0;
        uint64_t stateChanges = 0;
        std::vector<uint8_t> lastStates;
    };
    size_t minStateFrames(size_t frames) const;
    static uint32_t key(const Chanspec& cs)
    {
        return (uint32_t(cs.centerChannel) << 16) | cs.bandwidthMHz;
    }

    AntennaArray array_;
    CalibratorOptions opts_;
    std::map<uint32_t, Channel> channels_;
};

/** The receiver's method mirrored for an access point's transmit chains: turns a frame prepared
 *  in drive mode (FramePreparer::prepare, world-frame sensor pose) into a CalibrationFrame of
 *  the transmitter, for a PhaseCalibrator built with the transmitter's array. Its "antennas" are
 *  the transmit chains (stream m from chain m), its snapshots the receive antennas, its expected
 *  bearing the AoD of the robot seen from the AP. The receiver's own offsets are a common factor
 *  of each snapshot, so the receiver needs no calibration for this.
 *
 *  The preprocessing removes each stream's phase slope across subcarriers (cyclic shifts and
 *  sampling-time offset alike), which also removes the slope of the transmit steering: what
 *  remains of it is its value at the centre frequency. The frame's layout is therefore replaced
 *  by one whose frequencies all equal the centre frequency (narrowband expected steering). */
class TransmitChainFramer
{
public:
    /** False (out untouched) if the frame lacks geometry or does not hold every stream
     *  0..chains−1 of the transmitter (the calibration needs all chains in every frame). */
    bool make(
        const CalibrationFrame& rxFrame, const mrpt::math::TPose2D& apPose, unsigned chains,
        CalibrationFrame& out);

private:
    std::map<const SubcarrierLayout*, std::shared_ptr<const SubcarrierLayout>> narrowband_;
};

/** Calibration factors [rx][subcarrier of the layout]: e^{−jφ}·10^{−g/20}, as CsiPreprocessor
 *  applies them. */
Eigen::MatrixXcf calibrationFactors(
    const PhaseCalibration& c, const SubcarrierLayout& layout, unsigned nRx);

}  // namespace mrpt_wifi::calib
