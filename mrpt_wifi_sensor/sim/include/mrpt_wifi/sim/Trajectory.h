/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPose2D.h>
#include <mrpt/math/TTwist2D.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/sim/Scenario.h>

#include <vector>

namespace mrpt_wifi::sim
{
/** Ground-truth robot motion sampled at a fixed step (unicycle kinematics with speed and
 *  turn-rate limits), interpolated in between. */
class Trajectory
{
public:
    /** Integrates the scenario's motion over its duration; random goals come from `rng`. */
    static Trajectory generate(const Scenario& sc, mrpt::random::CRandomGenerator& rng);

    /** World pose of the robot base at time t (clamped to [0, duration]). */
    mrpt::math::TPose2D poseAt(double t_s) const;
    /** Body-frame velocity (vx, 0, ω) at time t. */
    mrpt::math::TTwist2D velocityAt(double t_s) const;

    double duration() const { return duration_; }
    double timeStep() const { return dt_; }
    const std::vector<mrpt::math::TPose2D>& samples() const { return poses_; }
    double pathLength_m() const { return pathLength_; }
    unsigned goalsReached() const { return goalsReached_; }

private:
    std::vector<mrpt::math::TPose2D> poses_;
    std::vector<mrpt::math::TTwist2D> twists_;
    double dt_ = 0.01, duration_ = 0, pathLength_ = 0;
    unsigned goalsReached_ = 0;
};

/** One wheel-odometry reading and the truth at the same instant. */
struct OdometrySample
{
    double time_s = 0;
    mrpt::math::TPose2D odometry;        //!< accumulated, in the odometry frame
    mrpt::math::TTwist2D velocityLocal;  //!< measured body-frame velocity
    mrpt::math::TPose2D truth;           //!< world-frame ground truth
};

/** Noisy, drifting odometry at spec.rate_Hz over the whole trajectory (OdometrySpec). */
std::vector<OdometrySample> simulateOdometry(
    const Trajectory& traj, const OdometrySpec& spec, mrpt::random::CRandomGenerator& rng);

}  // namespace mrpt_wifi::sim
