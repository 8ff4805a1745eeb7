/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <mrpt_wifi/sensor/Ros2StandardMessages.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

namespace mrpt_wifi::ros2
{
namespace
{
// The field lists of ROS 2's .msg files (Humble and later), comments left out. Types in the same
// package are unqualified, as in the files; readers resolve them in the package of the message.
const std::map<std::string, std::string>& bodies()
{
    static const std::map<std::string, std::string> m = {
        {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"},
        {"builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n"},
        {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
        {"std_msgs/ColorRGBA", "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n"},
        {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
        {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
        {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
        {"geometry_msgs/Pose", "Point position\nQuaternion orientation\n"},
        {"geometry_msgs/PoseStamped", "std_msgs/Header header\nPose pose\n"},
        {"geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"},
        {"geometry_msgs/PoseWithCovarianceStamped",
         "std_msgs/Header header\nPoseWithCovariance pose\n"},
        {"geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"},
        {"geometry_msgs/TransformStamped",
         "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"},
        {"nav_msgs/Path", "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n"},
        {"sensor_msgs/CompressedImage", "std_msgs/Header header\nstring format\nuint8[] data\n"},
        {"visualization_msgs/UVCoordinate", "float32 u\nfloat32 v\n"},
        {"visualization_msgs/MeshFile", "string filename\nuint8[] data\n"},
        {"visualization_msgs/Marker",
         "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\n"
         "int32 LINE_LIST=5\nint32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\n"
         "int32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\nint32 TRIANGLE_LIST=11\n"
         "int32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n"
         "std_msgs/Header header\n"
         "string ns\n"
         "int32 id\n"
         "int32 type\n"
         "int32 action\n"
         "geometry_msgs/Pose pose\n"
         "geometry_msgs/Vector3 scale\n"
         "std_msgs/ColorRGBA color\n"
         "builtin_interfaces/Duration lifetime\n"
         "bool frame_locked\n"
         "geometry_msgs/Point[] points\n"
         "std_msgs/ColorRGBA[] colors\n"
         "string texture_resource\n"
         "sensor_msgs/CompressedImage texture\n"
         "UVCoordinate[] uv_coordinates\n"
         "string text\n"
         "string mesh_resource\n"
         "MeshFile mesh_file\n"
         "bool mesh_use_embedded_materials\n"},
        {"visualization_msgs/MarkerArray", "Marker[] markers\n"},
        {"tf2_msgs/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"},
    };
    return m;
}

/** The complex types a body names, fully qualified (same-package names get the package). */
std::vector<std::string> dependenciesOf(const std::string& name)
{
    const std::string package = name.substr(0, name.find('/'));
    std::vector<std::string> out;
    const std::string& body = bodies().at(name);
    size_t pos = 0;
    while (pos < body.size())
    {
        const size_t eol = body.find('\n', pos);
        std::string type = body.substr(pos, body.find(' ', pos) - pos);
        pos = eol + 1;
        if (const auto b = type.find('['); b != std::string::npos) type.resize(b);
        if (type.find('/') == std::string::npos)
        {
            if (type.empty() || std::islower(static_cast<unsigned char>(type[0]))) continue;
            type = package + "/" + type;
        }
        out.push_back(type);
    }
    return out;
}

/** "pkg/Type" as a package resource name, "pkg/msg/Type". */
std::string resourceName(const std::string& type)
{
    const auto slash = type.find('/');
    return type.substr(0, slash) + "/msg" + type.substr(slash);
}

/** A body with its qualified field types spelled as the "MSG:" blocks name them (pkg/msg/Type):
 *  readers such as @foxglove/rosmsg match the two spellings literally. */
std::string withResourceNames(const std::string& body)
{
    std::string out;
    size_t pos = 0;
    while (pos < body.size())
    {
        const size_t eol = body.find('\n', pos);
        std::string line = body.substr(pos, eol - pos);
        pos = eol + 1;
        const size_t space = line.find(' ');
        const size_t slash = line.find('/');
        if (slash != std::string::npos && slash < space && line.find('/', slash + 1) > space)
            line.insert(slash, "/msg");
        out += line + "\n";
    }
    return out;
}

/** `name` ("pkg/Type") with each dependency once, depth first, in rosbag2's schema layout. */
MessageType makeType(const std::string& name)
{
    std::vector<std::string> order;
    std::vector<std::string> stack = dependenciesOf(name);
    std::reverse(stack.begin(), stack.end());
    while (!stack.empty())
    {
        const std::string t = stack.back();
        stack.pop_back();
        if (std::find(order.begin(), order.end(), t) != order.end()) continue;
        order.push_back(t);
        auto deps = dependenciesOf(t);
        stack.insert(stack.end(), deps.rbegin(), deps.rend());
    }
    std::string text = withResourceNames(bodies().at(name));
    for (const auto& t : order)
        text += std::string(80, '=') + "\nMSG: " + resourceName(t) + "\n" +
                withResourceNames(bodies().at(t));
    return {resourceName(name), text};
}

using eprosima::fastcdr::Cdr;

void put(Cdr& c, const Time& t)
{
    c << t.sec << t.nanosec;
}
void put(Cdr& c, const Header& h)
{
    put(c, h.stamp);
    c << h.frameId;
}
void put(Cdr& c, const Point& p)
{
    c << p.x << p.y << p.z;
}
void put(Cdr& c, const Quaternion& q)
{
    c << q.x << q.y << q.z << q.w;
}
void put(Cdr& c, const Pose& p)
{
    put(c, p.position);
    put(c, p.orientation);
}
void put(Cdr& c, const ColorRGBA& k)
{
    c << k.r << k.g << k.b << k.a;
}
void put(Cdr& c, const PoseStamped& p)
{
    put(c, p.header);
    put(c, p.pose);
}
void put(Cdr& c, const Marker& m)
{
    put(c, m.header);
    c << m.ns << m.id << m.type << m.action;
    put(c, m.pose);
    put(c, m.scale);
    put(c, m.color);
    put(c, m.lifetime);
    c << m.frameLocked;
    c << uint32_t(m.points.size());
    for (const auto& p : m.points) put(c, p);
    c << uint32_t(m.colors.size());
    for (const auto& k : m.colors) put(c, k);
    c << std::string();  // texture_resource
    put(c, Header{});    // texture: an empty sensor_msgs/CompressedImage
    c << std::string() << uint32_t(0);
    c << uint32_t(0);  // uv_coordinates
    c << m.text;
    c << std::string();                 // mesh_resource
    c << std::string() << uint32_t(0);  // mesh_file
    c << false;                         // mesh_use_embedded_materials
}
void put(Cdr& c, const TransformStamped& t)
{
    put(c, t.header);
    c << t.childFrameId;
    put(c, t.translation);
    put(c, t.rotation);
}

template <class Fill>
std::vector<uint8_t> cdrBytes(Fill&& fill)
{
    eprosima::fastcdr::FastBuffer buffer;
    Cdr cdr(buffer, Cdr::LITTLE_ENDIANNESS, Cdr::DDS_CDR);
    cdr.serialize_encapsulation();
    fill(cdr);
    const auto* p = reinterpret_cast<const uint8_t*>(buffer.getBuffer());
    return {p, p + cdr.getSerializedDataLength()};
}
}  // namespace

Time Time::fromSeconds(double t)
{
    // Whole seconds and the rounded fraction (as the ROS 1 header conversion): t·1e9 itself
    // would lose ~100 ns to double rounding at today's epoch times.
    Time out;
    const double whole = std::floor(t);
    auto sec = int64_t(whole);
    auto ns = int64_t(std::llround((t - whole) * 1e9));
    if (ns >= 1000000000) ++sec, ns -= 1000000000;
    out.sec = int32_t(sec);
    out.nanosec = uint32_t(ns);
    return out;
}

Quaternion Quaternion::fromYaw(double yaw)
{
    Quaternion q;
    q.z = std::sin(0.5 * yaw);
    q.w = std::cos(0.5 * yaw);
    return q;
}

const MessageType& poseStampedType()
{
    static const MessageType t = makeType("geometry_msgs/PoseStamped");
    return t;
}
const MessageType& poseWithCovarianceStampedType()
{
    static const MessageType t = makeType("geometry_msgs/PoseWithCovarianceStamped");
    return t;
}
const MessageType& pathType()
{
    static const MessageType t = makeType("nav_msgs/Path");
    return t;
}
const MessageType& markerArrayType()
{
    static const MessageType t = makeType("visualization_msgs/MarkerArray");
    return t;
}
const MessageType& tfMessageType()
{
    static const MessageType t = makeType("tf2_msgs/TFMessage");
    return t;
}

std::vector<uint8_t> serializeCdr(const PoseStamped& m)
{
    return cdrBytes([&](Cdr& c) { put(c, m); });
}
std::vector<uint8_t> serializeCdr(const PoseWithCovarianceStamped& m)
{
    return cdrBytes(
        [&](Cdr& c)
        {
            put(c, m.header);
            put(c, m.pose);
            c.serializeArray(m.covariance.data(), m.covariance.size());
        });
}
std::vector<uint8_t> serializeCdr(const PathMsg& m)
{
    return cdrBytes(
        [&](Cdr& c)
        {
            put(c, m.header);
            c << uint32_t(m.poses.size());
            for (const auto& p : m.poses) put(c, p);
        });
}
std::vector<uint8_t> serializeCdr(const MarkerArray& m)
{
    return cdrBytes(
        [&](Cdr& c)
        {
            c << uint32_t(m.markers.size());
            for (const auto& k : m.markers) put(c, k);
        });
}
std::vector<uint8_t> serializeCdr(const TFMessage& m)
{
    return cdrBytes(
        [&](Cdr& c)
        {
            c << uint32_t(m.transforms.size());
            for (const auto& t : m.transforms) put(c, t);
        });
}

}  // namespace mrpt_wifi::ros2
