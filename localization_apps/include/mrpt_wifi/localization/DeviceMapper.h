/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/Trajectory2D.h>

#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace mrpt_wifi::localization
{
/** One bearing ray in the world frame: from the receive array at (x, y), direction θ (and the
 *  mirror candidate of a linear array). */
struct BearingRay
{
    double t = 0;
    double x = 0, y = 0;                       //!< receive array position [m]
    double sensorYaw = 0;                      //!< receive array yaw [rad]
    double aoa = 0, mirror = 0, sigma = 0.05;  //!< in the sensor frame [rad]
    bool ambiguous = false;
    /** Uncertainty of the ray's origin when the trajectory is drifting odometry taken as exact
     *  (addOdometryDrift): position σ [m] and heading σ [rad] since the trajectory's start. */
    double poseStdXY = 0, poseStdYaw = 0;
};

/** Drift of dead-reckoning odometry: a random walk per metre travelled, as the simulator's
 *  `odometry` section (`sigma_xy_m_per_sqrt_m`, `sigma_yaw_deg_per_sqrt_m`). */
struct OdometryDrift
{
    double sigmaXY_perSqrtM = 0.01;    //!< position σ per √m travelled [m/√m]
    double sigmaYaw_perSqrtM = 0.005;  //!< heading σ per √m travelled [rad/√m] (0.29°)
};

struct DeviceMapOptions
{
    RobustBearingModel model;
    std::string loss = "cauchy";  //!< robust loss of the refinement
    double lossScale = 1.0;       //!< in units of σ
    double gridStep_m = 0.1;      //!< global search grid
    double margin_m = 2.0;        //!< search area: trajectory bounds grown by this, unless
    bool boundsGiven = false;     //!< ... bounds are given:
    double xmin = 0, xmax = 0, ymin = 0, ymax = 0;
    size_t maxGridRays = 400;  //!< rays used by the grid search (evenly subsampled)
    size_t minRays = 10;       //!< fewer: the device is reported as not localized
    double inlierSigmas = 3;   //!< |residual| < k·σ counts as inlier
    /** Bearing errors are correlated along the trajectory (same multipath nearby): the
     *  covariance is inflated by N_inliers / N_eff, N_eff = distinct cells of this size visited by
     *  the inlier rays' origins, and by the reduced χ² of the inliers when above 1. */
    double decorrelation_m = 0.5;
    /** With rays from a trajectory that is drifting odometry (BearingRay::poseStdXY/Yaw set by
     *  addOdometryDrift), the covariance gains the pose uncertainty of the inlier rays: the mean
     *  of σ_xy² + (range·σ_yaw)² over them, isotropic. The drift is common to all rays, so it
     *  does not average out as the bearing noise does. */
    bool includePoseUncertainty = true;
};

/** χ² quantile for 2 degrees of freedom at 95 %: a point lies inside the 95 % ellipse of a 2-D
 *  Gaussian when its Mahalanobis distance² is at most this. */
constexpr double kChi2TwoDof95 = 5.991;

/** Mahalanobis distance² of the offset (ex, ey) under the covariance xx, xy, yy [m²]; +∞ when
 *  the covariance is not positive definite. */
double mahalanobis2(double xx, double xy, double yy, double ex, double ey);

/** The square cell of side `size` [m] that (x, y) falls in: bearings received in one cell share
 *  their multipath error (DeviceMapOptions::decorrelation_m, GraphSlamOptions). */
std::pair<long, long> decorrelationCell(double x, double y, double size);

/** Per transmitter, bearings received close together share their multipath error: n bearings
 *  from c distinct cells (decorrelationCell) carry about c independent ones, so each σ grows by
 *  sqrt(n / c). With a cell size <= 0 every bearing counts (factor 1). */
class BearingDecorrelation
{
public:
    explicit BearingDecorrelation(double cell_m) : cell_m_(cell_m) {}
    /** A bearing of `transmitter` received at (x, y). */
    void add(const MacAddress& transmitter, double x, double y);
    /** sqrt(n / c) of `transmitter`; 1 for one never added. */
    double factor(const MacAddress& transmitter) const;

private:
    double cell_m_;
    std::map<MacAddress, std::pair<size_t, std::set<std::pair<long, long>>>> seen_;
};

struct DeviceEstimate
{
    MacAddress mac;
    std::string name;  //!< if known
    bool localized = false;
    std::string note;  //!< why not, or a caveat
    double x = 0, y = 0;
    double cov[3] = {0, 0, 0};  //!< xx, xy, yy [m²] (Ceres covariance, inflated: see options)
    double covInflation = 1;    //!< factor applied to Ceres' covariance
    double poseStd_m = 0;       //!< RMS pose uncertainty of the rays, added to cov (per axis)
    size_t rays = 0, inliers = 0;
    double medianResidual_deg = 0;
    double baseline_deg = 0;  //!< angular spread of the rays' directions at the estimate
};

/** Rays of each transmitter: bearings (AoA) placed on a trajectory (interpolated at their time,
 *  ⊕ the record's sensor pose). Bearings outside the trajectory's time span are counted in
 *  `warnings->outsideTrajectory`. */
std::map<MacAddress, std::vector<BearingRay>> raysFromBearings(
    const std::vector<BearingRecord>& bearings, const Trajectory2D& trajectory,
    InputWarnings* warnings = nullptr, double maxGap_s = 1.0);

/** Sets the origin uncertainty of every ray (BearingRay::poseStdXY/Yaw) for a trajectory that
 *  is dead-reckoning odometry taken as exact: after s metres travelled since the trajectory's
 *  start, heading σ_φ² = σ_yaw²·s and position σ² per axis = σ_xy²·s + ½·σ_yaw²·∫₀^s |p(s) −
 *  p(s')|² ds' (each heading error rotates the path driven after it: a loop back to the start
 *  cancels it). A systematic scale error is not included. */
void addOdometryDrift(
    std::map<MacAddress, std::vector<BearingRay>>& rays, const Trajectory2D& trajectory,
    const OdometryDrift& drift);

/** Robust triangulation of one device: global grid search of the mixture likelihood (mirror
 *  candidates included), then Ceres refinement with a robust loss, then covariance. */
DeviceEstimate triangulateDevice(const std::vector<BearingRay>& rays, const DeviceMapOptions& o);

/** A bearing an observer at an unknown position took to a transmitter at a known one. */
struct BearingToKnown
{
    mrpt::math::TPoint2D transmitter;
    double bearing_rad = 0;  //!< world frame, from the observer towards the transmitter
    double sigma_rad = 0.05;
};

/** Where the observer stood (WSR's localization from bearings to known robots): the point that
 *  triangulateDevice() finds from rays cast back from each transmitter. At least 2 bearings
 *  (DeviceMapOptions::minRays is lowered to 2). */
DeviceEstimate locateObserver(const std::vector<BearingToKnown>& bearings, DeviceMapOptions o = {});

/** Writes estimates as CSV (mac,name,x,y,cov_xx,cov_xy,cov_yy,...) and as a TransmitterMap
 *  YAML (localized devices only, one element, yaw 0). */
void saveDeviceCsv(const std::string& path, const std::vector<DeviceEstimate>& devices);
void saveDeviceYaml(const std::string& path, const std::vector<DeviceEstimate>& devices);

}  // namespace mrpt_wifi::localization
