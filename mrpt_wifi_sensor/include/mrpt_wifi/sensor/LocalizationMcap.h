/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// The --mcap output of the localization programs: estimated poses, the trajectory, bearing rays,
// transmitters and devices as ROS 2 standard messages in frame "map", so Foxglove (or any MCAP
// viewer that knows ROS 2 messages) shows them with no project code. Topics:
//   /pose          geometry_msgs/msg/PoseWithCovarianceStamped (or PoseStamped without
//                  covariance), one per estimate
//   /tf            tf2_msgs/msg/TFMessage map -> base_link, the same pose (viewers follow it)
//   /path          nav_msgs/msg/Path, the whole trajectory, once at the end (at most
//                  kMaxPathPoses poses, evenly thinned on long runs: /pose has every one)
//   /bearing_rays  visualization_msgs/msg/MarkerArray, one LINE_LIST per step (a segment per
//                  bearing, from the receive array along the bearing)
//   /transmitters, /devices  visualization_msgs/msg/MarkerArray: a SPHERE, a TEXT_VIEW_FACING
//                  label and, with a covariance, a flat CYLINDER as the 95 % ellipse
// Calls must come in time order (MCAP viewers play messages by log time).

#include <mrpt_wifi/sensor/McapWriter.h>
#include <mrpt_wifi/sensor/Ros2Messages.h>

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi::ros2
{
class LocalizationMcap
{
public:
    /** A point of the map: a transmitter or a device. cov = (xx, xy, yy) [m²] when known. */
    struct Landmark
    {
        std::string name;
        double x = 0, y = 0, z = 0;
        std::optional<std::array<double, 3>> cov;
    };
    /** One bearing ray: from the receive array at (x, y), direction in the map frame [rad],
     *  length [m]. */
    struct Ray
    {
        double x = 0, y = 0, angle = 0, length = 0;
    };

    /** withCovariance: /pose is PoseWithCovarianceStamped (else PoseStamped). */
    LocalizationMcap(
        const std::string& path, bool withCovariance,
        mcap::Compression compression = mcap::Compression::Zstd);

    /** An estimate at t [s since the epoch]; cov3 = row-major 3×3 over (x, y, phi) when
     *  known. Also appended to the trajectory written by close(). */
    void pose(
        double t, double x, double y, double phi, const std::array<double, 9>* cov3 = nullptr);
    /** The rays of one step (a viewer replaces the previous step's). */
    void bearingRays(double t, const std::vector<Ray>& rays);
    void transmitters(double t, const std::vector<Landmark>& list);
    void devices(double t, const std::vector<Landmark>& list);
    /** Poses /path holds at most: a live run of hours (100 poses/s) would otherwise keep every
     *  pose in memory to the end. Beyond it every other pose is dropped and the stride doubles,
     *  so the path spans the whole run with evenly spaced poses and its last one. */
    static constexpr size_t kMaxPathPoses = 10000;
    /** Writes /path (at the last pose's time) and closes the file; throws naming it on error. */
    void close();

    uint64_t messageCount() const { return writer_.messageCount(); }

private:
    void landmarks(
        const char* topic, uint16_t& channel, double t, const std::vector<Landmark>& list, float r,
        float g, float b);
    uint16_t channel(uint16_t& id, const char* topic, const MessageType& type);

    mcap::Writer writer_;
    bool withCovariance_;
    static constexpr uint16_t kNone = 0xFFFF;
    uint16_t poseChannel_ = kNone, tfChannel_ = kNone, pathChannel_ = kNone, raysChannel_ = kNone,
             txChannel_ = kNone, devChannel_ = kNone;
    struct Stamped
    {
        double t, x, y, phi;
    };
    std::vector<Stamped> trajectory_;  //!< every stride_-th pose, for /path
    size_t stride_ = 1, posesSeen_ = 0;
    Stamped last_{};  //!< the newest pose: /path always ends there
    bool closed_ = false;
};

}  // namespace mrpt_wifi::ros2
