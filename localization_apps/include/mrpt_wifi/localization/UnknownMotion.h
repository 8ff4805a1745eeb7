/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/poses/CPose2D.h>

#include <deque>
#include <optional>
#include <string>
#include <utility>

namespace mrpt_wifi::localization
{
/** Motion model for a robot whose motion is unknown (no odometry): a random walk whose spread is
 *  bounded by the robot's top speed, around a constant-velocity prediction.
 *
 *  Between two filter steps `dt` apart the pose changes by a Gaussian in the robot frame, with
 *  mean the predicted increment (ConstantVelocityPrediction: the filter's own estimate over the
 *  last `velocityWindow_s`, bounded by the top speed; zero when `constantVelocity` is off or no
 *  estimate exists yet) and
 *  \f[ \sigma_{xy} = v_{max}\sqrt{dt\,\tau}, \qquad \sigma_\phi = \omega_{max}\sqrt{dt\,\tau} \f]
 *  (per axis). Over any horizon `τ` (correlationTime_s) the accumulated walk therefore has a
 *  spread of `v_max·τ`: the distance the robot can cover in that time at top speed, however many
 *  steps the bearings cut it into (a per-step σ of `v_max·dt` would shrink the spread with the
 *  bearing rate and let the filter fall behind a moving robot). Steps longer than `maxStep_s`
 *  are capped there (the filter restarts its search rather than spreading over the whole map
 *  after a gap), and σ never falls below the floors (a particle cloud needs some jitter).
 *
 *  The member defaults are the plain model (one Gaussian, no forward-only prediction); the
 *  shipped share/localization/pf-localization-wifi.ini sets the measured, recommended values.
 *
 *  Used by wifi-pf-localization (no --odometry-tum) and by any program that feeds MRPT's particle
 *  filters without odometry: makeAction() gives the CActionRobotMovement2D to pass as the
 *  filter's action. */
struct UnknownMotion
{
    double maxSpeed_mps = 0.5;       //!< v_max: the robot's top speed [m/s]
    double maxTurnRate_dps = 90;     //!< ω_max [deg/s]
    double correlationTime_s = 0.2;  //!< τ: horizon over which the walk spreads v_max·τ
    double maxStep_s = 2.0;          //!< dt is capped at this [s]
    double minStdXY_m = 0.01;        //!< σ_xy floor [m]
    double minStdPhi_deg = 0.5;      //!< σ_φ floor [deg]
    /** Predict each step from the filter's recent estimates (constant velocity) instead of a
     *  zero-mean walk: a pure random walk lags behind a moving robot. */
    bool constantVelocity = true;
    double velocityWindow_s = 1.0;  //!< estimates this far back give the velocity [s]
    /** A robot that drives along its heading (differential drive, car): the predicted increment
     *  is the forward speed only, each particle moving along its own heading (no sideways
     *  component from the noise of the estimates). */
    bool forwardOnly = false;
    /** Heavy-tailed walk: this fraction of the filter's particles takes the walk of
     *  `wideCorrelationTime_s` instead of τ, so a tight τ tracks straight drives closely while
     *  the few wide steps catch the turns the constant-velocity prediction misses (the bearings
     *  then pick them). 0: a single Gaussian. */
    double wideFraction = 0.0;
    double wideCorrelationTime_s = 1.0;  //!< τ of the wide part
    /** In (0, 1]: without odometry, each bearing's log-likelihood is multiplied by this (on top
     *  of the map's CWiFiBearingMap bearing_weight), as OdometryMotion's does with odometry.
     *  Bearings a fraction of a second apart err alike, so counting them as independent makes
     *  the cloud narrower than the multipath allows. The shipped .ini keeps 1: 0.5 traded rooms
     *  on the development sweep (share/localization/README.md). */
    double bearingWeight = 1.0;

    /** σ of the position change per axis [m] and of the heading change [rad] over `dt_s`. */
    double stdXY(double dt_s) const;
    double stdPhi(double dt_s) const;

    /** The filter action for a step of `dt_s` seconds: mean `increment` (robot frame; zero for
     *  the pure random walk), the σ above (mmGaussian). With `wideFraction > 0` its poseChange
     *  is the mixture as weighted samples (CPosePDFParticles: 150 tight, 50 wide, weighted by
     *  their shares; MRPT's filter draws each particle's step from them); they come from MRPT's
     *  global random generator. */
    mrpt::obs::CActionRobotMovement2D::Ptr makeAction(
        double dt_s, const mrpt::poses::CPose2D& increment = {}) const;

    /** Reads `max_speed_mps`, `max_turn_rate_dps`, `correlation_time_s`, `max_step_s`,
     *  `min_std_xy`, `min_std_phi_deg`, `constant_velocity` (bool), `velocity_window_s`,
     *  `forward_only` (bool), `wide_fraction`, `wide_correlation_time_s`, `bearing_weight` from
     *  `section`
     *  (missing keys keep their value).
     *  Throws std::invalid_argument on non-positive speeds or times. */
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
    /** Throws std::invalid_argument naming the bad field. */
    void validate() const;
    std::string asString() const;
};

/** Makes sure MRPT's particle filter uses `action` as the step's motion, however wide it is.
 *  The filter takes the motion from CActionCollection::getBestMovementEstimation(), which
 *  skips every CActionRobotMovement2D whose pose change has a covariance determinant of 1e3 or
 *  more unless the action is marked as scan matching; with no motion left the filter throws
 *  "Action list does not contain any CActionRobotMovement2D ..." (in pf-localization's worker
 *  thread: an abort). Particles re-seeded over a large area (withReseeding(): 26 x 18 m at a
 *  re-seeding share of 0.2 is past the limit) or a fast unknown-motion walk over a long step
 *  get there. Such an action is marked as emScan2DMatching, the only way MRPT offers to have
 *  it taken whatever its spread; it is then stored with its pose change itself (not as an
 *  odometry reading plus motion model). Actions under the limit are left as they are. */
void keepUsableByMrptFilter(mrpt::obs::CActionRobotMovement2D& action);

/** Motion model for a robot with odometry: the odometry increment plus a heavy-tailed random
 *  walk whose spread grows with the distance driven and with time, not with the number of
 *  filter steps.
 *
 *  MRPT's Gaussian odometry model adds its σ floors (`[DummyOdometryParams]`) once per filter
 *  step: at 150 bearings/s that is a walk of 6°/√s in heading, so the filter all but ignores the
 *  odometry and follows the bearings wherever multipath biases them (and a live filter, taking
 *  several bearings per step, gets another model than the offline one). Here a step over `dt`
 *  seconds and `d` metres driven has, per axis,
 *  \f[ \sigma_{xy}^2 = q_{xy,m}^2\,d + q_{xy,s}^2\,dt, \qquad
 *      \sigma_\phi^2 = q_{\phi,m}^2\,d + q_{\phi,s}^2\,dt \f]
 *  (random walks per metre and per second: the odometry's slip and drift), the same however the
 *  bearings cut the drive into steps. On top of it, jumps (a compound Poisson process): at
 *  `jumpRate_hz` per second a particle's pose jumps by a Gaussian of `jumpStdXY_m` and
 *  `jumpStdPhi_deg`, so in a step of dt the share 1 − exp(−rate·dt) of the particles jumps: a
 *  filter that settled on a slightly wrong pose (most often the heading, after a turn whose
 *  bearings multipath bent) keeps particles that explore, and the bearings pick them, while the
 *  rest follows the odometry closely. Per time, not per step: a share of every step (2 % taking
 *  30× the step's σ, before) made the walk √(0.98 + 0.02·30²) = 4.4 times as wide as the tight
 *  one, its shape depend on how the bearings cut the drive into steps (offline one per bearing,
 *  live several), and let a filter in a room with weak geometry (two of three APs side by side)
 *  turn 15-20° away from its odometry.
 *
 *  Read from the `.ini`'s `[OdometryMotion]` section by wifi-pf-localization and wifi-localize;
 *  without that section both use MRPT's model as pf-localization does. */
struct OdometryMotion
{
    double stdXY_per_sqrt_m = 0.03;      //!< q_xy,m [m/√m]
    double stdPhi_deg_per_sqrt_m = 1.0;  //!< q_φ,m [deg/√m]
    double stdXY_per_sqrt_s = 0.02;      //!< q_xy,s [m/√s]
    double stdPhi_deg_per_sqrt_s = 0.5;  //!< q_φ,s [deg/√s]
    double maxStep_s = 2.0;              //!< dt is capped at this [s]
    double jumpRate_hz = 0.5;            //!< jumps per particle and second
    double jumpStdXY_m = 0.1;            //!< σ of a jump per axis [m]
    double jumpStdPhi_deg = 3.0;         //!< σ of a jump in heading [deg]
    /** In (0, 1]: while odometry drives the filter, each bearing's log-likelihood is multiplied
     *  by this (on top of the map's CWiFiBearingMap bearing_weight). With the odometry carrying
     *  the particles between spots, bearings from one spot, which err alike, need not count as
     *  independent evidence. Without odometry UnknownMotion's bearing_weight applies instead:
     *  each motion model has its own, not the map. */
    double bearingWeight = 1.0;

    /** σ of the position change per axis [m] and of the heading change [rad] for a step of
     *  `dt_s` seconds and `distance_m` metres driven (the tight part). */
    double stdXY(double dt_s, double distance_m) const;
    double stdPhi(double dt_s, double distance_m) const;

    /** The filter action for the odometry `increment` (robot frame) over `dt_s` seconds: a
     *  Gaussian (mmGaussian with the σ above), or with jumps the mixture (the share
     *  1 − exp(−rate·dt) with the jump added) as weighted samples as UnknownMotion::makeAction's,
     *  drawn from MRPT's global generator. */
    mrpt::obs::CActionRobotMovement2D::Ptr makeAction(
        double dt_s, const mrpt::poses::CPose2D& increment) const;

    /** Reads `std_xy_per_sqrt_m`, `std_phi_deg_per_sqrt_m`, `std_xy_per_sqrt_s`,
     *  `std_phi_deg_per_sqrt_s`, `max_step_s`, `jump_rate_hz`, `jump_std_xy_m`,
     *  `jump_std_phi_deg`, `bearing_weight` from `section` (missing keys keep their value).
     *  Throws std::invalid_argument naming a bad value. */
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
    void validate() const;
    std::string asString() const;
};

/** The tempering of the bearings by the motion model driving the filter, on top of the map's own
 *  bearing_weight: `odometry`'s with odometry (1 with MRPT's model, without [OdometryMotion]),
 *  `unknown`'s without. The one rule for wifi-pf-localization and wifi-localize. */
double motionBearingWeight(
    bool withOdometry, const UnknownMotion& unknown, const std::optional<OdometryMotion>& odometry);

/** The constant-velocity prediction of UnknownMotion: fed with the filter's estimate after each
 *  step, it predicts the next step's pose increment in the robot frame.
 *
 *  The velocity (linear and angular) is the displacement of the estimate between the newest
 *  estimate and the one `velocityWindow_s` before it, divided by their time difference; the
 *  increment over `dt` is that motion applied from the newest estimate, expressed in its frame,
 *  its length bounded by `maxSpeed_mps·dt` and its turn by `maxTurnRate_dps·dt`. Until the
 *  history spans half the window (a fresh start, a gap longer than `maxStep_s`, or time going
 *  backwards: a new run) the prediction is zero, i.e. the random walk. */
class ConstantVelocityPrediction
{
public:
    explicit ConstantVelocityPrediction(const UnknownMotion& motion) : m_(motion) {}

    /** The filter's estimate (PF mean) at time `t_s` [s], after that step's observations. */
    void addEstimate(double t_s, const mrpt::math::TPose2D& estimate);
    /** The predicted increment from the newest estimate to time `t_s` (robot frame). */
    mrpt::poses::CPose2D predictIncrement(double t_s) const;
    void reset() { hist_.clear(); }

private:
    UnknownMotion m_;
    std::deque<std::pair<double, mrpt::math::TPose2D>> hist_;
};

}  // namespace mrpt_wifi::localization
