/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/graphs/CNetworkOfPoses.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <array>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace mrpt_wifi::localization
{
/** One phase of solveBearingGraph (placement search, AP initialisation, a Ceres solve, ...):
 *  its wall time summed over every time it ran and how often it ran. */
struct GraphSlamPhase
{
    std::string name;
    double seconds = 0;
    size_t runs = 0;
};

struct GraphSlamOptions
{
    double nodePeriod_s = 0.5;  //!< a pose node every this much odometry time
    // Odometry edge noise per edge: σ = max(floor, k·sqrt(distance)) (+ rotation term for yaw)
    double odoSigmaXY_perSqrtM = 0.02;
    double odoSigmaYaw_perSqrtM = 0.0175;  //!< rad/√m (1°)
    double odoSigmaYaw_perSqrtRad = 0.02;
    double odoSigmaXY_min = 0.005, odoSigmaYaw_min = 0.002;
    /** Systematic odometry errors, common to every edge: a scale error (σ of the factor: 0.02
     *  for 2 %) and a heading drift per metre travelled (σ [rad/m]; 0.3°/m), a wheeled robot
     *  on an office floor. With either > 0 both are estimated with these priors (the joint
     *  covariance then includes them: bearings alone cannot observe the scale); 0 and 0: the
     *  odometry has none. */
    double odoScaleStd = 0.02, odoYawDriftStd_radPerM = 0.3 * M_PI / 180;
    /** > 0: the bearings of each transmitter count as one per cell of this size [m] that their
     *  receive positions visit (each σ × sqrt(bearings / cells)): bearings taken close together
     *  share their multipath error, so thousands of them are not thousands of independent
     *  measurements, and the covariance (apCovariance) is honest about it; 0: independent. */
    double bearingDecorrelation_m = 0.5;

    bool useAoa = true, useAod = true;
    /** An AoA with an alternative direction (BearingRecord::hasAoaAlternative) explains a pose
     *  by whichever of its directions is closer, with each direction's own σ (a max-mixture);
     *  false: one direction with the σ that reaches both. The localization apps set it from
     *  the map's aoa_alternative_share. */
    bool useAoaAlternatives = false;
    double minStd_rad = 0.0349;  //!< floor on bearing σ (2°)
    double stdScale = 1.0;
    std::string loss = "cauchy";  //!< robust loss of bearing edges: cauchy | huber | none
    double lossScale = 1.0;       //!< in units of σ

    /** Known APs: stay fixed and define the world frame. The trajectory's initial placement
     *  is multi-hypothesis: the `placementHypotheses` best distinct placements of a global
     *  search over the first 30 s, each optimised, the lowest final cost wins (symmetric AP
     *  layouts and the mirror ambiguity of linear arrays make several placements look alike at
     *  the start). Only when the placement cannot be trusted (the first 30 s hear fewer than 3
     *  of the APs, or the best placed solution leaves fewer than `placementInlierShare` of the
     *  bearings within 3 σ or did not converge) is (alignEstimatedAps) the estimated-AP
     *  solution, moved onto the map by the rigid transform aligning its APs with the known
     *  ones, optimised as a further start: the unknown-AP machinery costs more than everything
     *  else and is not needed when the placement is clear.
     *  Unknown: APs are estimated, gauge = first pose fixed. */
    bool apsKnown = false;
    int placementHypotheses = 4;
    double placementInlierShare = 0.6;
    /** Unknown APs: compute each AP's position covariance from the joint solution
     *  (ceres::Covariance; the trajectory's uncertainty is marginalised, gauge = first pose). */
    bool apCovariance = false;
    bool alignEstimatedAps = true;
    /** Unknown APs: besides the start from all rays on the odometry, a start grown window by
     *  window: the first `growthWindow_s` seconds are solved (APs triangulated from their rays),
     *  then each further window is appended with the odometry continued from the last solved
     *  pose, the APs re-triangulated on that trajectory and the graph solved again. Drift then
     *  only acts within one window, not along the whole drive (a heading bias of 0.5 deg/s
     *  turns a 5-lap odometry by 2 turns' worth of degrees: rays from it place no AP). The start
     *  with the lower final cost wins. 0 = only the start from the odometry. */
    double growthWindow_s = 30;
    /** Ceres iterations of each solve; a solve that stops before Ceres' convergence criteria
     *  hold sets GraphSlamResult::converged = false (the apps warn). */
    int maxIterations = 500;
    /** Unknown APs with the grown start also run: Ceres iterations of the start from APs
     *  triangulated on the whole odometry. On a long drifting drive that start lies far from
     *  any solution and would spend hundreds of iterations of the whole problem (30 min in a
     *  building: 228, 27 s) to end above the grown start; a start still moving after this many
     *  competes with the cost it has reached (reported as not converged if it wins). */
    int odometryStartIterations = 50;
    int threads = 2;
    bool verbose = false;
    /** Grown start: the stages before the last free only the poses of their newest 4 windows
     *  (the older ones stay as solved) and, with unknown APs, keep of the older bearings one per
     *  AP and cell of this size [m] of the solved poses (they hold the APs), so a stage costs
     *  what a few windows and the area hold, not the whole drive so far; the last stage and the
     *  other starts use every bearing. 0: no older bearing is kept. */
    double growthThinning_m = 1.0;
    /** Called with one line per finished phase (placement, AP initialisation, each solve,
     *  grown-start windows at most every few seconds), with the elapsed time: what the
     *  programs print while a long drive is solved. Empty: silent. */
    std::function<void(const std::string&)> progress;
    /** Called each time a phase ends, with that run's name and seconds (runs = 1): for
     *  measurements per phase, e.g. the peak memory of each (bench_graph_slam_scale). */
    std::function<void(const GraphSlamPhase&)> phaseFinished;
};

/** The problem: odometry (trajectory in its own frame) or an existing MRPT pose graph with node
 *  times, bearings, and (optionally) the APs. */
struct GraphSlamInput
{
    Trajectory2D odometry;  //!< always: node times and odometry between them
    /** Optional: odometry edges (and node poses) from an MRPT .graph whose node k is at
     *  `odometry.t[k]` (then nodePeriod_s is not used). */
    const mrpt::graphs::CNetworkOfPoses2DInf* graph = nullptr;
    std::vector<BearingRecord> bearings;
    TransmitterMap aps;  //!< known poses (apsKnown) or names/arrays only; may be empty if unknown
    /** Known APs: the starts to optimise (rigid transforms from the odometry frame to the map,
     *  e.g. from a particle filter's estimate); the lowest final cost wins. Empty: searched
     *  (placementHypotheses, alignEstimatedAps). */
    std::vector<mrpt::math::TPose2D> placements;
};

struct GraphSlamResult
{
    Trajectory2D poses;         //!< node poses, solved
    Trajectory2D initialPoses;  //!< node poses before optimisation (odometry, placed)
    TransmitterMap aps;         //!< solved (or fixed) APs
    mrpt::graphs::CNetworkOfPoses2DInf graph;  //!< poses + AP vertices, odometry edges
    size_t aoaEdges = 0, aodEdges = 0, odometryEdges = 0;
    InputWarnings warnings;
    size_t apsWithoutBearings = 0;
    double initialCost = 0, finalCost = 0, solveTime_s = 0, totalTime_s = 0;
    int iterations = 0;
    /** Ceres met its convergence criteria (not stopped by maxIterations or time). */
    bool converged = false;
    std::string solverReport;
    /** With apCovariance: xx, xy, yy [m²] of each AP of `aps` (same order); zeros for APs
     *  without bearings. apCovarianceOk is false when Ceres could not compute it (rank
     *  deficient: an AP seen from too few places). */
    std::vector<std::array<double, 3>> apCov;
    bool apCovarianceOk = false;
    /** Bearing edges whose residual at the solution is within 3 of their σ, the median
     *  |residual|/σ and the median |residual| [deg]. Bearings from a calibrated receiver leave a
     *  few degrees; biased ones (a calibration of another boot, antenna jumps) tens. */
    double bearingsWithin3Sigma = 0, medianWhitenedResidual = 0, medianResidual_deg = 0;
    /** Which start won, and how many were optimised (known APs: placements and the aligned
     *  estimated-AP solution; unknown APs: the odometry start and the grown start). */
    std::string placement;
    size_t hypotheses = 1;
    /** With GraphSlamOptions::odoScaleStd / odoYawDriftStd_radPerM: the estimated odometry
     *  scale factor and heading drift [rad/m]. */
    double odometryScale = 1, odometryYawDrift_radPerM = 0;
    /** Where the time went, in the order the phases first ran (summed over every start). */
    std::vector<GraphSlamPhase> phases;
    /** How many times an unknown AP was initialised from its rays (triangulateDevice): 0 when
     *  the APs are known and their placement is clear. */
    size_t apTriangulations = 0;
};

/** Builds and solves the graph (Ceres). Throws std::runtime_error on an empty odometry, no usable
 *  bearings, an unconnected graph (.graph input) or bearings that never overlap the odometry. */
GraphSlamResult solveBearingGraph(const GraphSlamInput& in, const GraphSlamOptions& opt);

/** Global placement of an odometry trajectory in the frame of known APs: the rigid transform
 *  maximising the robust bearing likelihood of the bearings in the first `window_s` seconds
 *  (grid over position and yaw, then a finer grid). */
/** The `maxCandidates` best distinct placements (≥ 1.5 m or 45° apart on the coarse grid),
 *  each refined, best first. */
std::vector<mrpt::math::TPose2D> placeTrajectoryCandidates(
    const Trajectory2D& odometry, const std::vector<BearingRecord>& bearings,
    const TransmitterMap& aps, double window_s, size_t maxCandidates);

mrpt::math::TPose2D placeTrajectory(
    const Trajectory2D& odometry, const std::vector<BearingRecord>& bearings,
    const TransmitterMap& aps, double window_s = 30);

}  // namespace mrpt_wifi::localization
