/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/slam/CMonteCarloLocalization2D.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/DeviceMapper.h>
#include <mrpt_wifi/localization/ParticleRecovery.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/localization/WindowSmoother.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi::localization
{
/** The first wifiBearingMap an .ini's `[MetricMap]` creates, as MRPT's apps build it; a
 *  relative transmitters_file not found from the working directory is taken relative to
 *  `iniDir`. Throws naming the problem (no such map, no transmitters). */
CWiFiBearingMap::Ptr wifiMapFromIni(
    const mrpt::config::CConfigFileBase& ini, const std::string& iniDir);

/** The box `[LocalizationExperiment] init_PDF_min/max_x/y` of a uniform initial distribution
 *  (init_PDF_mode = 1): where a kidnapped robot can be, the map's area when the map sets none. */
std::optional<mrpt::math::TBoundingBox> initialPdfArea(const mrpt::config::CConfigFileBase& ini);

/** The map's area and the init_PDF box, one source of truth by default: a map without an area
 *  of its own takes initialPdfArea() (true returned). When the .ini gives both and they
 *  disagree, `warning` (if given) says how and what to do: a box reaching outside the area also
 *  widens the area to cover both (a robot the box allows must not die at the area's edge); an
 *  area larger than the box is kept (the filter starts in the box). Empty when they agree. */
bool boundByInitialPdf(
    CWiFiBearingMap& map, const mrpt::config::CConfigFileBase& ini, std::string* warning = nullptr);

/** "x A..B, y C..D m" */
std::string boxText(const mrpt::math::TBoundingBox& box);

/** MRPT's Gaussian odometry model as its pf-localization configures it for observation-only
 *  rawlogs: `[DummyOdometryParams] minStdXY` [m] and `minStdPHI` [deg] floors. */
mrpt::obs::CActionRobotMovement2D::TMotionModelOptions odometryMotionModel(
    const mrpt::config::CConfigFileBase& ini);

/** Options of the live filter that the pf-localization .ini does not have: section
 *  `[wifi-localize]` of the same file (all optional). Without odometry the motion model is the
 *  file's `[UnknownMotion]`, as for wifi-pf-localization. */
struct LiveLocalizerOptions
{
    /** `max_bearings_per_step`: observations per filter step (sensory frame), 2 by default;
     *  0: all that are queued. 1 is what the offline wifi-pf-localization does (one step per
     *  bearing); a step of n bearings applies the odometry noise floor × sqrt(n), the spread n
     *  single steps would have added (with an `[OdometryMotion]` section the spread depends on
     *  time and distance alone). The model is the same, the filter is not: a step multiplies
     *  its n likelihoods before the motion spreads the particles again, and after a smoother
     *  solve tens of bearings are queued. Without odometry, 20 queued at a time (live-replay,
     *  development rooms 39-42 and 47-52, seeds 1-3): within 0.3 m in 25 of 30 runs taken all
     *  at once, 27 two per step, 28 offline. */
    size_t maxBearingsPerStep = 2;
    /** `max_queue_s`: with max_bearings_per_step set, the bearings more than this [s] older
     *  than now (step()'s `now_s`) go into the next step beyond the cap, so a filter that falls
     *  behind (a slow machine, a long smoother solve) catches up with larger steps instead of
     *  lagging ever further. */
    double maxQueue_s = 0.25;
    /** `bearing_bias_std_deg`: σ of a bias common to one transmitter's bearings (multipath seen
     *  alike from nearby poses) that the particles cannot know of: its effect on the pose
     *  (bearingBiasCovariance at the estimate, for the angles the map uses, over the
     *  transmitters heard in the last 5 s) is added to the particles' covariance in
     *  uncertainty(). 0: the particles' covariance alone. */
    double bearingBiasStd_deg = 3.0;

    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& section);
};

/** MRPT's Monte Carlo localization (CMonteCarloLocalization2D + CParticleFilter) with the WiFi
 *  bearing map, fed one observation at a time as they arrive, for live use.
 *
 *  Configured from the same .ini as pf-localization / wifi-pf-localization
 *  ([LocalizationExperiment] particles_count and init_PDF_* (mode 1), [PF_options],
 *  [KLD_options], [DummyOdometryParams], [MetricMap]). Odometry readings accumulate; each
 *  step() takes the oldest bearings queued (up to max_bearings_per_step, more when they are
 *  over max_queue_s late) as one sensory frame, with the odometry increment since the last
 *  step as the action (the `[OdometryMotion]` model if the file has that section, else
 *  MRPT's Gaussian model with the DummyOdometryParams floor, as MRPT's app does), or, while no
 *  odometry has been seen, the `[UnknownMotion]` model around the constant-velocity prediction
 *  from this filter's own estimates; either way `[ParticleRecovery]` re-seeds particles while
 *  the bearings disagree with the estimate: the same models as wifi-pf-localization. The map's
 *  area is the init_PDF box unless its creationOpts set one. Not thread-safe. */
class LiveLocalizer
{
public:
    /** `iniDir`: a relative transmitters_file not found from the working directory is taken
     *  relative to it. Throws naming the .ini's problem. */
    LiveLocalizer(const mrpt::config::CConfigFileBase& ini, const std::string& iniDir);

    void addOdometry(const mrpt::obs::CObservationOdometry& odo);
    /** Bearings of unknown transmitters are counted and dropped. */
    void addBearing(const CObservationWiFiBearing::Ptr& b);
    size_t pendingBearings() const { return pending_.size(); }

    /** One filter step with the queued bearings; false (nothing done) if there are none.
     *  `now_s`: the current time on the bearings' clock (wifi-localize: the host's UNIX time,
     *  which stamps live CSI); bearings more than max_queue_s older than it, or than the newest
     *  queued one if that is later, go into this step beyond max_bearings_per_step. So a
     *  pipeline that falls behind anywhere, the CSI's bearing estimation included, catches
     *  up. Without it (a replay) the newest queued bearing is the reference. */
    bool step(std::optional<double> now_s = std::nullopt);

    /** Weighted mean and the particles' spread (sqrt of the largest position variance). */
    mrpt::math::TPose2D mean() const;
    /** The pose to report: mean() refined by the `[WindowSmoother]` (as wifi-pf-localization
     *  does offline; without odometry its fitted track) once it has an accepted solve; else
     *  mean(). */
    mrpt::math::TPose2D estimate() const { return estimateGiven(mean()); }
    const WindowSmoother& smoother() const { return smoother_; }
    double spread_m() const;
    /** Covariances of (x, y, φ) [m², m², rad²] of estimate(). */
    struct Uncertainty
    {
        /** The particles' weighted covariance (MRPT's getCovarianceAndMean: the heading's
         *  spread around the mean, wrapped). */
        mrpt::math::CMatrixDouble33 particles;
        /** The particles' spread about estimate() (`particles` plus the outer product of
         *  estimate() − particlesMean; while the smoother gives no estimate, plus the last
         *  such offset it gave, in every direction), plus the transmitters' bearing bias
         *  (bearing_bias_std_deg): a converged cloud is as narrow as the bearings agree with
         *  each other, not as their common error. Alone its 95 % ellipse held 25-77 % of the
         *  errors after convergence with odometry (development rooms 1-10, live). */
        mrpt::math::CMatrixDouble33 reported;
        /** The particles' weighted mean (mean()), from the same pass. */
        mrpt::math::TPose2D particlesMean;
    };
    /** One pass over the particles for all three. */
    Uncertainty uncertainty() const;
    /** Timestamp of the newest bearing of the last step [s, UNIX]. */
    double lastStepTime() const { return lastStepTime_; }
    size_t steps() const { return steps_; }
    const LiveLocalizerOptions& options() const { return opts_; }
    uint64_t bearingsUsed() const { return bearingsUsed_; }
    /** Of bearingsUsed(), those with an angle the map weighs (use_aoa / use_aod, within
     *  max_std_deg): 0 with bearings used means the filter never left its prior. */
    uint64_t bearingsWeighed() const { return bearingsWeighed_; }
    uint64_t unknownTransmitter() const { return unknown_; }
    bool hasOdometry() const { return lastOdo_.has_value(); }

    const mrpt::slam::CMonteCarloLocalization2D& particles() const { return pdf_; }
    const CWiFiBearingMap& wifiMap() const { return *wifiMap_; }
    const UnknownMotion& unknownMotion() const { return motion_; }
    const ParticleRecoveryOptions& recoveryOptions() const { return recoveryOptions_; }
    const ParticleRecovery& recovery() const { return *recovery_; }
    /** Whether the map's area came from the init_PDF box (the map's creationOpts set none). */
    bool areaFromInitialPdf() const { return areaFromInitPdf_; }
    /** boundByInitialPdf()'s warning: the .ini's map area and init_PDF box disagree ("" when
     *  they agree or only one is given). */
    const std::string& areaWarning() const { return areaWarning_; }

private:
    /** estimate() with the particles' mean already computed (one pass over them, not two). */
    mrpt::math::TPose2D estimateGiven(const mrpt::math::TPose2D& particlesMean) const
    {
        return smoothed_ ? *smoothed_ : particlesMean;
    }

    LiveLocalizerOptions opts_;
    mrpt::maps::CMultiMetricMap::Ptr map_ = std::make_shared<mrpt::maps::CMultiMetricMap>();
    CWiFiBearingMap::Ptr wifiMap_;
    mrpt::slam::CMonteCarloLocalization2D pdf_;
    mrpt::bayes::CParticleFilter pf_;
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions odoModel_;
    std::optional<OdometryMotion> odoMotion_;  //!< [OdometryMotion], if the .ini has one
    double mapBearingWeight_ = 1.0;            //!< the map's own bearing_weight, before a motion's
    std::optional<mrpt::poses::CPose2D> lastOdo_, odoAtLastStep_;
    std::vector<CObservationWiFiBearing::Ptr> pending_;
    /** Newest bearing time [s] per transmitter used, and the receive array's pose on the
     *  robot (of the newest bearing): for uncertainty(). */
    std::map<MacAddress, double> heard_;
    mrpt::math::TPose2D sensorOnRobot_;
    UnknownMotion motion_;
    ConstantVelocityPrediction cv_{motion_};
    ParticleRecoveryOptions recoveryOptions_;
    std::optional<ParticleRecovery> recovery_;
    WindowSmoother smoother_{WindowSmootherOptions(), TransmitterMap()};
    std::optional<mrpt::math::TPose2D> smoothed_;
    /** The smoother's estimate minus the particles' mean at the last step it gave one. When
     *  it stops giving one, the mean is reported and its error is as large as this offset
     *  showed, whatever the particles' spread: a narrow cloud can lag the robot. The robot
     *  turns since, so the offset counts in every direction. */
    std::optional<mrpt::math::TPose2D> lastSmootherOffset_;
    bool areaFromInitPdf_ = false;
    std::string areaWarning_;
    double lastStepTime_ = 0;
    size_t steps_ = 0;
    uint64_t bearingsUsed_ = 0, bearingsWeighed_ = 0, unknown_ = 0;
};

/** The lag of every pose output of a live run (wifi-localize's summary: p50, p99, max), kept as
 *  a count per 0.1 ms, the resolution the summary prints: memory follows the range of the lags,
 *  not the length of the run, and each percentile is the printed value of the same rank among
 *  all the lags (floor(q·n), the last one for q = 1). */
class LagRecord
{
public:
    static constexpr double kResolution_s = 1e-4;

    void add(double lag_s);
    uint64_t count() const { return count_; }
    /** The lag of rank min(n − 1, floor(q·n)) in increasing order, to kResolution_s; NaN when
     *  nothing was added. */
    double percentile(double q) const;
    /** Distinct 0.1 ms values held (what the record costs). */
    size_t bins() const { return counts_.size(); }

private:
    std::map<long long, uint64_t> counts_;  //!< lag / kResolution_s, rounded -> how many
    uint64_t count_ = 0;
};

/** Live device mapping: wifi-iot-map's machinery (raysFromBearings + triangulateDevice) on the
 *  AoA bearings and odometry seen so far. The inputs are kept exactly as readRawlog() would read
 *  them from a rawlog of the same observations (odometry sorted and strictly increasing in time,
 *  bearings stably sorted by time), so the map after the last observation equals
 *  `wifi-iot-map --rawlog` on that rawlog with the same options. Options: section
 *  `[wifi-localize]`, keys `map_devices` (bool), `map_min_std_deg`, `map_outlier_prob`,
 *  `map_loss`, `map_grid_m`, `map_update_period_s`, `map_odometry_drift_xy` [m/√m] and
 *  `map_odometry_drift_yaw_deg` [deg/√m] (wifi-iot-map --trust-odometry's defaults: the
 *  odometry's drift enters the devices' σ, see addOdometryDrift). */
class LiveDeviceMapper
{
public:
    /** Reads the options; enabled() is false unless `map_devices = true`. */
    LiveDeviceMapper(const mrpt::config::CConfigFileBase& ini, const std::string& section);

    bool enabled() const { return enabled_; }
    double updatePeriod_s() const { return updatePeriod_s_; }
    const DeviceMapOptions& options() const { return opts_; }

    void addOdometry(const mrpt::obs::CObservationOdometry& odo);
    /** Bearings without AoA are ignored (as wifi-iot-map does). */
    void addBearing(const CObservationWiFiBearing& b);
    size_t bearings() const { return bearings_.size(); }

    /** Triangulates every device from everything seen so far (the costly part: a grid search
     *  per device) and keeps the result in devices(). */
    void update();
    const std::vector<DeviceEstimate>& devices() const { return devices_; }
    const InputWarnings& warnings() const { return warnings_; }

private:
    bool enabled_ = false;
    double updatePeriod_s_ = 2.0;
    DeviceMapOptions opts_;
    OdometryDrift drift_;  //!< map_odometry_drift_xy, map_odometry_drift_yaw_deg
    std::vector<std::pair<double, mrpt::math::TPose2D>> odometry_;
    std::vector<BearingRecord> bearings_;
    std::vector<DeviceEstimate> devices_;
    InputWarnings warnings_;
};

}  // namespace mrpt_wifi::localization
