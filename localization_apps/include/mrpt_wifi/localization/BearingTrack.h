/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/TBoundingBox.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi::localization
{
/** How a robot without odometry is assumed to move, for solveBearingTrack: a prior on the
 *  change of its motion from one node step to the next, not on the motion itself (a robot
 *  driving straight at constant speed costs nothing, whatever the speed). */
struct TrackMotionPrior
{
    double nodePeriod_s = 0.5;  //!< a pose node every this much time
    /** σ of the change of the forward (and sideways) speed [m/s²]: the step between two nodes
     *  may differ from the one before by accelStd·h² (h = nodePeriod_s). */
    double accelStd_mps2 = 2.0;
    double turnAccelStd_radps2 = 120 * M_PI / 180;  //!< the same for the turn rate [rad/s²]
    /** σ of the sideways part of a step [m]: a differential-drive or car-like robot moves along
     *  its heading (its wheels do not slip sideways), which ties the heading to the track. A
     *  large value: holonomic. */
    double lateralStd_m = 0.02;
    /** The robot never drives backwards: a backward step costs as a sideways one (this resolves
     *  the 180° heading ambiguity of a track, and the mirror image of a linear array). The apps
     *  take it from `[UnknownMotion] forward_only`, the one place that says how the robot
     *  moves without odometry. */
    bool forwardOnly = false;

    /** Reads `track_node_period_s`, `track_accel_std`, `track_turn_accel_std_deg` and
     *  `track_lateral_std_m` from `section` (missing keys keep their value); throws
     * std::invalid_argument naming the section and keys on a non-positive σ. */
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& section);
};

struct TrackInput
{
    /** The nodes are at t1, t1 − h, … down to the first at or after t0. */
    double t0 = 0, t1 = 0;
    std::vector<BearingRecord> bearings;  //!< those outside [t0, t1] or of unknown APs: ignored
    TransmitterMap aps;                   //!< known, fixed: they define the frame
    /** Starting tracks (world frame), each interpolated at the node times (its nearest end
     *  beyond them); each is optimised and the lowest final cost wins, except that the first
     *  start keeps its place unless another one's cost is lower by more than
     *  `firstStartMargin` (a hypothesis kept until the bearings clearly favour another: in a
     *  room with a symmetry two places fit a standing robot's bearings almost alike). */
    std::vector<Trajectory2D> starts;
    double firstStartMargin = 0;
    /** The area the robot can be in (x, y): a node outside it costs (distance / 5 cm)². */
    std::optional<mrpt::math::TBoundingBox> area;
};

struct TrackResult
{
    Trajectory2D poses;  //!< at the node times, oldest first
    size_t bearingEdges = 0;
    double finalCost = 0;
    double medianWhitenedResidual = 0;  //!< the bearings' median |residual|/σ at the solution
    size_t start = 0;                   //!< index of the winning start
};

/** A robot's path over [t0, t1] from bearings to known transmitters and a motion prior alone
 *  (no odometry): pose nodes every nodePeriod_s, each bearing predicted from the pose
 *  interpolated between its two nodes (robust loss, σ floor and decorrelation of `bearings` as
 *  in solveBearingGraph: minStd_rad, stdScale, loss, lossScale, bearingDecorrelation_m, useAoa,
 *  useAod, maxIterations, threads), and the motion prior between consecutive steps.
 *
 *  Why: a particle filter of poses only cannot hold a velocity, so without odometry each step
 *  guesses the motion and the estimate lags on turns and speed changes; a window of bearings
 *  with a smooth, along-the-heading track sees where the robot went.
 *
 *  Throws std::runtime_error on t1 < t0 + nodePeriod_s, no start, no usable bearing or no
 *  usable solution. */
TrackResult solveBearingTrack(
    const TrackInput& in, const TrackMotionPrior& prior, const GraphSlamOptions& bearings);

}  // namespace mrpt_wifi::localization
