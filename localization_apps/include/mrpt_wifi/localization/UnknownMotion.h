/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/obs/CActionRobotMovement2D.h>

#include <string>

namespace mrpt_wifi::localization
{
/** Motion model for a robot whose motion is unknown (no odometry): a zero-mean random walk whose
 *  spread is bounded by the robot's top speed.
 *
 *  Between two filter steps `dt` apart the pose changes by a zero-mean Gaussian in the robot
 *  frame with
 *  \f[ \sigma_{xy} = v_{max}\sqrt{dt\,\tau}, \qquad \sigma_\phi = \omega_{max}\sqrt{dt\,\tau} \f]
 *  (per axis). Over any horizon `τ` (correlationTime_s) the accumulated walk therefore has a
 *  spread of `v_max·τ`: the distance the robot can cover in that time at top speed, however many
 *  steps the bearings cut it into (a per-step σ of `v_max·dt` would shrink the spread with the
 *  bearing rate and let the filter fall behind a moving robot). Steps longer than `maxStep_s`
 *  are capped there (the filter restarts its search rather than spreading over the whole map
 *  after a gap), and σ never falls below the floors (a particle cloud needs some jitter).
 *
 *  Used by wifi-pf-localization (no --odometry-tum) and by any program that feeds MRPT's particle
 *  filters without odometry: makeAction() gives the CActionRobotMovement2D to pass as the
 *  filter's action. */
struct UnknownMotion
{
    double maxSpeed_mps = 0.5;       //!< v_max: the robot's top speed [m/s]
    double maxTurnRate_dps = 90;     //!< ω_max [deg/s]
    double correlationTime_s = 1.0;  //!< τ: horizon over which the walk spreads v_max·τ
    double maxStep_s = 2.0;          //!< dt is capped at this [s]
    double minStdXY_m = 0.01;        //!< σ_xy floor [m]
    double minStdPhi_deg = 0.5;      //!< σ_φ floor [deg]

    /** σ of the position change per axis [m] and of the heading change [rad] over `dt_s`. */
    double stdXY(double dt_s) const;
    double stdPhi(double dt_s) const;

    /** The filter action for a step of `dt_s` seconds: zero mean, the σ above (mmGaussian). */
    mrpt::obs::CActionRobotMovement2D::Ptr makeAction(double dt_s) const;

    /** Reads `max_speed_mps`, `max_turn_rate_dps`, `correlation_time_s`, `max_step_s`,
     *  `min_std_xy`, `min_std_phi_deg` from `section` (missing keys keep their value).
     *  Throws std::invalid_argument on non-positive speeds or times. */
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
    /** Throws std::invalid_argument naming the bad field. */
    void validate() const;
    std::string asString() const;
};

}  // namespace mrpt_wifi::localization
