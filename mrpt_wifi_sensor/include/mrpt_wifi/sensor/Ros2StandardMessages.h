/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// ROS 2's standard messages for poses, trajectories and map markers (geometry_msgs, nav_msgs,
// visualization_msgs, tf2_msgs): the structs, their ros2msg definitions (dependencies appended
// as rosbag2 writes an MCAP schema) and their CDR serialization through Debian's libfastcdr.
// Only what this project writes; field names follow the ROS definitions.

#include <mrpt_wifi/sensor/Ros2Messages.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mrpt_wifi::ros2
{
/** builtin_interfaces/msg/Time (also Duration's layout). */
struct Time
{
    int32_t sec = 0;
    uint32_t nanosec = 0;
    /** Seconds since the epoch, rounded to the nanosecond. */
    static Time fromSeconds(double t);
    uint64_t nanoseconds() const { return uint64_t(int64_t(sec)) * 1000000000ull + nanosec; }
};
struct Header
{
    Time stamp;
    std::string frameId;
};
/** geometry_msgs/msg/Point and Vector3 (the same layout). */
struct Point
{
    double x = 0, y = 0, z = 0;
};
struct Quaternion
{
    double x = 0, y = 0, z = 0, w = 1;
    static Quaternion fromYaw(double yaw);
};
struct Pose
{
    Point position;
    Quaternion orientation;
};
struct PoseStamped
{
    Header header;
    Pose pose;
};
/** geometry_msgs/msg/PoseWithCovarianceStamped; covariance row-major over
 *  (x, y, z, rot x, rot y, rot z). */
struct PoseWithCovarianceStamped
{
    Header header;
    Pose pose;
    std::array<double, 36> covariance{};
};
struct PathMsg
{
    Header header;
    std::vector<PoseStamped> poses;
};
struct ColorRGBA
{
    float r = 0, g = 0, b = 0, a = 1;
};
/** visualization_msgs/msg/Marker (texture, uv_coordinates and mesh fields written empty). */
struct Marker
{
    enum Type : int32_t
    {
        ARROW = 0,
        CUBE = 1,
        SPHERE = 2,
        CYLINDER = 3,
        LINE_STRIP = 4,
        LINE_LIST = 5,
        SPHERE_LIST = 7,
        POINTS = 8,
        TEXT_VIEW_FACING = 9
    };
    enum Action : int32_t
    {
        ADD = 0,
        DELETE = 2,
        DELETEALL = 3
    };
    Header header;
    std::string ns;
    int32_t id = 0;
    int32_t type = SPHERE;
    int32_t action = ADD;
    Pose pose;
    Point scale;  //!< geometry_msgs/Vector3
    ColorRGBA color;
    Time lifetime;  //!< builtin_interfaces/Duration; 0: forever
    bool frameLocked = false;
    std::vector<Point> points;
    std::vector<ColorRGBA> colors;
    std::string text;
};
struct MarkerArray
{
    std::vector<Marker> markers;
};
/** geometry_msgs/msg/TransformStamped. */
struct TransformStamped
{
    Header header;
    std::string childFrameId;
    Point translation;  //!< geometry_msgs/Vector3
    Quaternion rotation;
};
/** tf2_msgs/msg/TFMessage. */
struct TFMessage
{
    std::vector<TransformStamped> transforms;
};

const MessageType& poseStampedType();
const MessageType& poseWithCovarianceStampedType();
const MessageType& pathType();
const MessageType& markerArrayType();
const MessageType& tfMessageType();

/** Encapsulation header (CDR little-endian) + XCDR1 body, as ROS 2's rmw writes it. */
std::vector<uint8_t> serializeCdr(const PoseStamped& m);
std::vector<uint8_t> serializeCdr(const PoseWithCovarianceStamped& m);
std::vector<uint8_t> serializeCdr(const PathMsg& m);
std::vector<uint8_t> serializeCdr(const MarkerArray& m);
std::vector<uint8_t> serializeCdr(const TFMessage& m);

}  // namespace mrpt_wifi::ros2
