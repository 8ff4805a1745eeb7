/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPose2D.h>

#include <string>
#include <vector>

namespace mrpt_wifi::calib
{
/** Planar robot poses over time (robot base in some fixed frame), interpolated at the time of
 *  each CSI frame. Times are UNIX seconds (mrpt::Clock::toDouble), as in TUM files. */
class PoseTrack
{
public:
    /** Adds a sample; samples may come in any order (sorted on first lookup). */
    void add(double t_s, const mrpt::math::TPose2D& pose);
    size_t size() const { return samples_.size(); }
    bool empty() const { return samples_.empty(); }
    double startTime() const;
    double endTime() const;

    /** Pose at t, linear in x, y and in the (wrapped) heading between the two neighbouring
     *  samples. False if t is outside the track or the neighbours are more than `maxGap_s`
     *  apart (the robot's motion in between is unknown). */
    bool at(double t_s, mrpt::math::TPose2D& out) const;
    double maxGap_s = 1.0;

    /** Every pose p becomes origin ⊕ p: odometry (which starts at 0,0,0) placed in the frame the
     *  transmitter position is given in. */
    PoseTrack transformed(const mrpt::math::TPose2D& origin) const;

    /** Reads a TUM trajectory (`t x y z qx qy qz qw`, '#' comments); the heading is the yaw of
     *  the quaternion. Throws std::runtime_error naming the file and line. */
    static PoseTrack fromTumFile(const std::string& path);

private:
    struct Sample
    {
        double t;
        mrpt::math::TPose2D pose;
    };
    void ensureSorted() const;
    mutable std::vector<Sample> samples_;
    mutable bool sorted_ = true;
};

}  // namespace mrpt_wifi::calib
