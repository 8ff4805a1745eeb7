/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sensor/LocalizationMcap.h>
#include <mrpt_wifi/sensor/Ros2StandardMessages.h>

namespace mrpt_wifi::ros2
{
namespace
{
const char* kMapFrame = "map";

uint64_t toNs(double t)
{
    return Time::fromSeconds(t).nanoseconds();
}

Header mapHeader(double t)
{
    return {Time::fromSeconds(t), kMapFrame};
}

Pose planarPose(double x, double y, double phi)
{
    Pose p;
    p.position = {x, y, 0};
    p.orientation = Quaternion::fromYaw(phi);
    return p;
}
}  // namespace

LocalizationMcap::LocalizationMcap(
    const std::string& path, bool withCovariance, mcap::Compression compression)
    : writer_(path, mcap::WriterOptions{compression}), withCovariance_(withCovariance)
{
}

uint16_t LocalizationMcap::channel(uint16_t& id, const char* topic, const MessageType& type)
{
    if (id == kNone) id = writer_.addRos2Channel(topic, type.name, type.definition);
    return id;
}

void LocalizationMcap::pose(
    double t, double x, double y, double phi, const std::array<double, 9>* cov3)
{
    last_ = {t, x, y, phi};
    if (posesSeen_++ % stride_ == 0)
    {
        trajectory_.push_back(last_);
        if (trajectory_.size() > kMaxPathPoses)
        {
            // Keep poses 0, 2, 4, … (posesSeen_ multiples of the doubled stride).
            size_t kept = 0;
            for (size_t i = 0; i < trajectory_.size(); i += 2) trajectory_[kept++] = trajectory_[i];
            trajectory_.resize(kept);
            stride_ *= 2;
        }
    }
    if (withCovariance_)
    {
        PoseWithCovarianceStamped m;
        m.header = mapHeader(t);
        m.pose = planarPose(x, y, phi);
        // (x, y, phi) into ROS's (x, y, z, rot x, rot y, rot z); phi is rotation about z.
        const int idx[3] = {0, 1, 5};
        if (cov3)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) m.covariance[idx[r] * 6 + idx[c]] = (*cov3)[r * 3 + c];
        writer_.write(
            channel(poseChannel_, "/pose", poseWithCovarianceStampedType()), toNs(t),
            serializeCdr(m));
    }
    else
    {
        PoseStamped m{mapHeader(t), planarPose(x, y, phi)};
        writer_.write(channel(poseChannel_, "/pose", poseStampedType()), toNs(t), serializeCdr(m));
    }
    TFMessage tf;
    TransformStamped ts;
    ts.header = mapHeader(t);
    ts.childFrameId = "base_link";
    ts.translation = {x, y, 0};
    ts.rotation = Quaternion::fromYaw(phi);
    tf.transforms.push_back(ts);
    writer_.write(channel(tfChannel_, "/tf", tfMessageType()), toNs(t), serializeCdr(tf));
}

void LocalizationMcap::bearingRays(double t, const std::vector<Ray>& rays)
{
    Marker m;
    m.header = mapHeader(t);
    m.ns = "bearing_rays";
    m.type = Marker::LINE_LIST;
    m.scale.x = 0.03;  // line width [m]
    m.color = {1.0f, 0.6f, 0.0f, 0.9f};
    for (const auto& r : rays)
    {
        m.points.push_back({r.x, r.y, 0});
        m.points.push_back(
            {r.x + r.length * std::cos(r.angle), r.y + r.length * std::sin(r.angle), 0});
    }
    // The same id each step: a viewer replaces the previous step's rays.
    MarkerArray a;
    a.markers.push_back(m);
    writer_.write(
        channel(raysChannel_, "/bearing_rays", markerArrayType()), toNs(t), serializeCdr(a));
}

void LocalizationMcap::landmarks(
    const char* topic, uint16_t& id, double t, const std::vector<Landmark>& list, float r, float g,
    float b)
{
    MarkerArray a;
    int32_t next = 0;
    for (const auto& l : list)
    {
        Marker s;
        s.header = mapHeader(t);
        s.ns = topic + 1;
        s.id = next++;
        s.type = Marker::SPHERE;
        s.pose = planarPose(l.x, l.y, 0);
        s.pose.position.z = l.z;
        s.scale = {0.3, 0.3, 0.3};
        s.color = {r, g, b, 1.0f};
        a.markers.push_back(s);

        Marker text = s;
        text.id = next++;
        text.type = Marker::TEXT_VIEW_FACING;
        text.pose.position.z = l.z + 0.4;
        text.scale = {0, 0, 0.3};  // text height
        text.color = {1, 1, 1, 1};
        text.text = l.name;
        a.markers.push_back(text);

        if (l.cov)
        {
            // The 95 % ellipse (chi² 2 dof = 5.991) as a flat cylinder: axes along the
            // covariance's eigenvectors, diameters 2·sqrt(5.991·eigenvalue).
            const auto [xx, xy, yy] = *l.cov;
            const double mean = 0.5 * (xx + yy);
            const double rad = std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
            const double l1 = std::max(0.0, mean + rad), l2 = std::max(0.0, mean - rad);
            const double angle = 0.5 * std::atan2(2 * xy, xx - yy);
            Marker e = s;
            e.id = next++;
            e.type = Marker::CYLINDER;
            e.pose = planarPose(l.x, l.y, angle);
            e.pose.position.z = l.z;
            e.scale = {2 * std::sqrt(5.991 * l1), 2 * std::sqrt(5.991 * l2), 0.01};
            e.color = {r, g, b, 0.3f};
            a.markers.push_back(e);
        }
    }
    writer_.write(channel(id, topic, markerArrayType()), toNs(t), serializeCdr(a));
}

void LocalizationMcap::transmitters(double t, const std::vector<Landmark>& list)
{
    landmarks("/transmitters", txChannel_, t, list, 0.2f, 0.4f, 1.0f);
}

void LocalizationMcap::devices(double t, const std::vector<Landmark>& list)
{
    landmarks("/devices", devChannel_, t, list, 0.1f, 0.8f, 0.2f);
}

void LocalizationMcap::close()
{
    if (closed_) return;
    closed_ = true;
    if (!trajectory_.empty())
    {
        if (trajectory_.back().t != last_.t) trajectory_.push_back(last_);
        PathMsg path;
        const double tEnd = trajectory_.back().t;
        path.header = mapHeader(tEnd);
        for (const auto& s : trajectory_)
            path.poses.push_back({mapHeader(s.t), planarPose(s.x, s.y, s.phi)});
        writer_.write(channel(pathChannel_, "/path", pathType()), toNs(tEnd), serializeCdr(path));
    }
    writer_.close();
}

}  // namespace mrpt_wifi::ros2
