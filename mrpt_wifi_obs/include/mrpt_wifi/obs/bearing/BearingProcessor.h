/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/bearing/BearingEstimator.h>
#include <mrpt_wifi/obs/bearing/BearingTracker.h>

#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace mrpt_wifi::bearing
{
/** The whole chain for a stream of CSI observations: preprocessing, one window per
 *  transmitter, an estimator, and the bearing observation. Not thread-safe. */
class BearingProcessor
{
public:
    struct Options
    {
        size_t windowCapacity = 32;   //!< frames kept per transmitter
        double windowMaxAge_s = 1.0;  //!< older frames are not combined
        /** Estimate once every `stride` accepted frames of a transmitter (1: every frame). */
        unsigned stride = 1;
        /** With odometry: a window combines only the frames taken while the robot moved less
         *  than this (translation [m], rotation [rad]) before its newest frame, so that they
         *  share the direct path's bearing; reflections still decorrelate over that motion. */
        double maxWindowTranslation_m = 0.15;
        double maxWindowRotation_rad = 3.0 * M_PI / 180;
        /** Without odometry: a window combines only the frames taken this long before its
         *  newest [s] (0: up to windowMaxAge_s). A robot may be moving or turning, and frames
         *  combined over 0.8 s of a turn (8 frames at 10 frames/s) smear the bearing. */
        double maxWindowSpanWithoutOdometry_s = 0.15;
        /** Odometry older than this before the newest CSI frame is forgotten [s]. */
        double odometryHistory_s = 5.0;
        /** AoD of a transmitter without a transmit-chain calibration (CleanCsi::txCalibration):
         *  every real AP's chains have their own unknown phases, so such an AoD is not a
         *  bearing. false: dropped (hasAod = false); true: reported as the estimator found it. */
        bool uncalibratedAod = false;
        /** Per-transmitter tracking over time (BearingTracker): where a window supports
         *  several directions (the other endfire, the mirror, a second path), the one the
         *  transmitter's track predicts from the earlier windows and the odometry is reported,
         *  and a bearing the confident track contradicts gets a σ that reaches the track.
         *  nullopt: on for the `default` estimator, off for the others. */
        std::optional<bool> tracking;
        BearingTracker::Options tracker;
        /** Synthetic aperture (estimator `sar`): sensor labels of the peers' recordings of this
         *  robot's packets, each with the peer's MAC. Such frames are kept for the estimator,
         *  not estimated on. */
        std::map<std::string, MacAddress> peerRecordings;
        /** Synthetic aperture: at most one estimate per transmitter per this many seconds. */
        double apertureInterval_s = 1.0;
    };

    BearingProcessor(
        CsiPreprocessor preprocessor, std::unique_ptr<BearingEstimator> estimator, Options options);
    ~BearingProcessor();
    BearingProcessor(BearingProcessor&&) noexcept;
    BearingProcessor& operator=(BearingProcessor&&) noexcept;

    bool tracking() const { return tracking_; }
    /** What the tracks said about the last bearing (valid when tracking() and process()
     *  returned a bearing). */
    const BearingTracker::Decision& lastTrackDecision() const { return lastDecision_; }
    /** The directions the last window supported (the estimator's first), given to the tracker. */
    const std::vector<BearingCandidate>& lastCandidates() const { return candidates_; }

    /** Transmitter arrays for AoD: one per MAC, and/or a default for all. */
    void setTransmitterArray(const MacAddress& mac, AntennaArray array);
    void setDefaultTransmitterArray(AntennaArray array);

    /** Robot odometry at time t, in any fixed frame (e.g. CObservationOdometry::odometry;
     *  in time order). Optional: without it every frame of a window (by age) is combined,
     *  as for a robot assumed static, which is what the live sensor does. */
    void addOdometry(mrpt::Clock::time_point t, const mrpt::math::TPose2D& odometry);
    bool hasOdometry() const { return !odometry_.empty(); }
    /** Odometry interpolated at t; nullopt outside the known span (±0.25 s at the ends). */
    std::optional<mrpt::math::TPose2D> odometryAt(mrpt::Clock::time_point t) const;

    /** Runs the chain on one frame (a peer's recording of this robot, Options::peerRecordings,
     *  is only kept). AoD only for transmitters whose chains are calibrated
     *  (Options::uncalibratedAod), its σ widened by the calibration's AoD residual. Returns the
     *  bearing (sensor label: the CSI's + "_AOA"; its
     *  CObservationBearingRange gets "_AOA_BEARING"), or nullptr when the frame was rejected
     *  (`reason` says why), is not due (stride), or the estimator could not produce one. */
    CObservationWiFiBearing::Ptr process(
        const CObservationWiFiCSI& csi, RejectReason* reason = nullptr);

    CsiPreprocessor& preprocessor() { return pre_; }
    BearingEstimator& estimator() { return *est_; }
    /** The preprocessed frame and the estimator's result of the last process() call. */
    const CleanCsi* lastFrame() const { return lastFrame_; }
    const BearingResult& lastResult() const { return lastResult_; }
    const std::vector<const CleanCsi*>& lastWindow() const { return frames_; }

private:
    const AntennaArray* txArrayOf(const MacAddress& mac) const;
    /** Drops the older frames of frames_ taken too far (odometry) from the newest. */
    void limitWindowByMotion();
    /** The estimator's bearing plus the other directions the window's CSI supports (local
     *  maxima of its wideband Bartlett spectrum, matched to the result's delay if it has one). */
    void findCandidates(const BearingResult& res);
    /** Runs the tracker on lastResult_ and applies its decision to it. */
    void track(const CObservationWiFiCSI& csi);

    CsiPreprocessor pre_;
    std::unique_ptr<BearingEstimator> est_;
    Options opts_;
    TransmitterWindows windows_;
    std::map<MacAddress, AntennaArray> txArrays_;
    std::optional<AntennaArray> defaultTxArray_;
    std::map<MacAddress, unsigned> sinceLast_;
    TransmitterWindows peerWindows_;             //!< peers' recordings of this robot, by peer MAC
    std::map<MacAddress, double> lastAperture_;  //!< time of each peer's last estimate [s]
    std::vector<const CleanCsi*> frames_;
    std::deque<std::pair<double, mrpt::math::TPose2D>> odometry_;  //!< (time [s], pose)
    const CleanCsi* lastFrame_ = nullptr;
    BearingResult lastResult_;
    bool tracking_ = false;
    BearingTracker tracker_;
    BearingTracker::Decision lastDecision_;
    std::vector<BearingCandidate> candidates_;
    struct CandidateScan;  // spectrum workspace (BearingMath, not installed)
    std::unique_ptr<CandidateScan> scan_;
};

}  // namespace mrpt_wifi::bearing
