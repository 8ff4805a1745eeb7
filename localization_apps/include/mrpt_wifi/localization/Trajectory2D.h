/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPose2D.h>

#include <string>
#include <vector>

namespace mrpt_wifi::localization
{
/** A planar trajectory: poses at increasing UNIX times. */
struct Trajectory2D
{
    std::vector<double> t;
    std::vector<mrpt::math::TPose2D> poses;

    size_t size() const { return t.size(); }
    bool empty() const { return t.empty(); }
    void push_back(double time, const mrpt::math::TPose2D& p)
    {
        t.push_back(time), poses.push_back(p);
    }

    /** Reads a TUM file (`t x y z qx qy qz qw`, '#' comments); yaw from the quaternion, z
     *  ignored. Throws std::runtime_error with file:line; sorts by time, rejects duplicates. */
    static Trajectory2D fromTumFile(const std::string& path);
    /** Reads the WSR Toolbox dataset's CSV trajectories: motion capture rows `t, -, x, y, z`
     *  (heading 0: not recorded) or odometry / tracking-camera rows `sec, nsec, x, y, z, qx,
     *  qy, qz, qw, ...`. Throws std::runtime_error with file:line. */
    static Trajectory2D fromWsrCsv(const std::string& path);
    /** fromWsrCsv() for `.csv` files, fromTumFile() otherwise. */
    static Trajectory2D fromFile(const std::string& path);
    /** Writes TUM (z = 0, rotation about z). */
    void saveTum(const std::string& path, const std::string& comment = {}) const;
    /** One TUM line of saveTum() (with its newline), for writers that flush pose by pose. */
    static std::string tumLine(double time, const mrpt::math::TPose2D& pose);

    /** Pose at time `time` by linear interpolation (yaw on the circle). False if `time` is
     *  outside [t.front(), t.back()] or the neighbours are more than `maxGap_s` apart. */
    bool interpolate(double time, mrpt::math::TPose2D& out, double maxGap_s = 1.0) const;
};

/** Summary statistics of errors. */
struct ErrorStats
{
    size_t count = 0;
    double rmse = 0, mean = 0, median = 0, p90 = 0, max = 0;
    std::string asString(const char* unit = "m") const;
};
ErrorStats computeStats(std::vector<double> errors);

/** Absolute trajectory error as evo computes it (`evo_ape --align`): estimate poses associated
 *  with ground truth by time (truth interpolated at the estimate's stamps), the rigid SE(2)
 *  transform that best maps estimate positions onto truth (Umeyama/Horn, no scale), then
 *  position errors. `align = false` compares in the given frames. `correctScale` also scales
 *  the estimate (evo's `--correct_scale`, Sim(2)): what is left is the error of its shape, as
 *  for a map whose scale nothing observed (bearings with estimated APs). */
struct AteResult
{
    ErrorStats stats;
    std::vector<double> times, errors;  //!< per associated pose
    mrpt::math::TPose2D alignment;      //!< applied to the estimate (after `scale`)
    double scale = 1;                   //!< applied to the estimate first (correctScale)
    size_t unmatched = 0;               //!< estimate poses without truth at their time
};
AteResult absoluteTrajectoryError(
    const Trajectory2D& estimate, const Trajectory2D& truth, bool align = true,
    bool correctScale = false);

/** Rigid 2-D transform T minimising Σ |T(a_i) − b_i|² (closed form). */
mrpt::math::TPose2D alignRigid2D(
    const std::vector<mrpt::math::TPoint2D>& a, const std::vector<mrpt::math::TPoint2D>& b);

/** Similarity: s and T minimising Σ |T(s·a_i) − b_i|² (Umeyama). */
struct Similarity2D
{
    mrpt::math::TPose2D pose;
    double scale = 1;
};
Similarity2D alignSimilarity2D(
    const std::vector<mrpt::math::TPoint2D>& a, const std::vector<mrpt::math::TPoint2D>& b);

}  // namespace mrpt_wifi::localization
