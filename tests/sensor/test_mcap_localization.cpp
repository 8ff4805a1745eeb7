/* mrpt_wifi — a localization program's --mcap output (issue 55) read back by independent code
 * (tests/sensor/mcap_check.mjs: npm's @mcap/core, @foxglove/rosmsg,
 * @foxglove/rosmsg2-serialization) and compared with the program's own text output: wifi-graphslam
 * on a small synthetic world (its trajectory_tum.txt and aps.yaml; the bearing rays from its input
 * bearings on that trajectory). */
#include <gtest/gtest.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "../apps/SyntheticWorld.h"
#include "../support/TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

namespace
{
std::string npmTools()
{
    for (const char* d : {MRPT_WIFI_NPM_TOOLS, MRPT_WIFI_NPM_TOOLS_IN_SOURCE})
        if (std::filesystem::exists(std::string(d) + "/node_modules/@mcap/core")) return d;
    return {};
}

std::string num(double v)
{
    char b[40];
    std::snprintf(b, sizeof(b), "%.17g", v);
    return b;
}
std::string ns(double t)
{
    const double whole = std::floor(t);
    return "\"" +
           std::to_string(
               uint64_t(whole) * 1000000000ull + uint64_t(std::llround((t - whole) * 1e9))) +
           "\"";
}
std::string point(double x, double y, double z = 0)
{
    return "{\"x\":" + num(x) + ",\"y\":" + num(y) + ",\"z\":" + num(z) + "}";
}
std::string pose(double x, double y, double phi, double z = 0)
{
    return "{\"position\":" + point(x, y, z) +
           ",\"orientation\":{\"x\":0,\"y\":0,\"z\":" + num(std::sin(phi / 2)) +
           ",\"w\":" + num(std::cos(phi / 2)) + "}}";
}
const char* kMapHeader = "{\"frame_id\":\"map\"}";  // the stamp is checked against the log time
}  // namespace

TEST(McapLocalization, GraphSlamPosesPathRaysAndApsMatchItsTextOutput)
{
    if (test::run("node --version").exitCode != 0 || npmTools().empty())
    {
        const std::string why = "no node or npm packages (scripts/install-deps.sh)";
        if (std::getenv("CI")) FAIL() << why;
        GTEST_SKIP() << why;
    }
    test::TempDir tmp;
    loctest::WorldOptions o;
    o.duration_s = 20;
    const auto w = loctest::makeWorld(
        loctest::makeAps(
            {{0.3, 4.7, -0.785}, {9.7, 4.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}}),
        o);
    std::ofstream(tmp.file("aps.yaml")) << w.aps.asYamlText();
    writeBearingCsv(tmp.file("bearings.csv"), w.bearings);
    w.odometry.saveTum(tmp.file("odometry.txt"));
    const std::string mcap = tmp.file("gs.mcap");
    const auto r = test::run(
        test::binDir() + "/wifi-graphslam --no-plots -b " + tmp.file("bearings.csv") +
        " --odometry-tum " + tmp.file("odometry.txt") + " --aps " + tmp.file("aps.yaml") +
        " --sensor-pose 0.1 0 0 0 0 0 -o " + tmp.file("gs") + " --mcap " + mcap);
    ASSERT_EQ(r.exitCode, 0) << r.output;

    // What the program wrote as text, and the bearings it read.
    const auto traj = Trajectory2D::fromTumFile(tmp.file("gs/trajectory_tum.txt"));
    const auto aps = TransmitterMap::fromYamlFile(tmp.file("gs/aps.yaml"));
    ASSERT_GT(traj.size(), 10u);
    BearingCsvOptions co;
    co.sensorPose = {0.1, 0, 0};
    co.names = &aps;
    auto bearings = readBearingCsv(tmp.file("bearings.csv"), co);
    std::stable_sort(
        bearings.begin(), bearings.end(), [](const auto& a, const auto& b) { return a.t < b.t; });

    std::vector<std::string> msgs;
    const auto add = [&](const std::string& topic, double t, const std::string& message)
    {
        msgs.push_back(
            "{\"topic\":\"" + topic + "\",\"logTime\":" + ns(t) +
            ",\"partial\":true,\"message\":" + message + "}");
    };
    // Transmitters first: a sphere and a label each (known APs: no covariance ellipse).
    {
        std::string markers;
        int id = 0;
        for (const auto& ap : aps.transmitters())
        {
            for (const bool label : {false, true})
            {
                markers += std::string(markers.empty() ? "" : ",") + "{\"header\":" + kMapHeader +
                           ",\"ns\":\"transmitters\",\"id\":" + std::to_string(id++) +
                           ",\"type\":" + (label ? "9" : "2") + ",\"action\":0,\"pose\":" +
                           pose(ap.pose.x, ap.pose.y, 0, label ? 0.4 : 0) + ",\"text\":\"" +
                           (label ? ap.name : "") + "\"}";
            }
        }
        add("/transmitters", traj.t.front(), "{\"markers\":[" + markers + "]}");
    }
    size_t next = 0, rays = 0;
    while (next < bearings.size() && bearings[next].t <= traj.t.front()) ++next;
    std::string pathPoses;
    for (size_t k = 0; k < traj.size(); ++k)
    {
        const auto& p = traj.poses[k];
        add("/pose", traj.t[k],
            "{\"header\":" + std::string(kMapHeader) + ",\"pose\":" + pose(p.x, p.y, p.phi) + "}");
        add("/tf", traj.t[k],
            "{\"transforms\":[{\"header\":" + std::string(kMapHeader) +
                ",\"child_frame_id\":\"base_link\",\"transform\":{\"translation\":" +
                point(p.x, p.y) + ",\"rotation\":{\"x\":0,\"y\":0,\"z\":" +
                num(std::sin(p.phi / 2)) + ",\"w\":" + num(std::cos(p.phi / 2)) + "}}}]}");
        pathPoses += std::string(k ? "," : "") + "{\"header\":" + kMapHeader +
                     ",\"pose\":" + pose(p.x, p.y, p.phi) + "}";
        // Each AoA since the previous pose: a segment from the array (robot pose interpolated
        // at the bearing's time, plus the sensor pose) to the AP it measures.
        std::string points;
        for (; k > 0 && next < bearings.size() && bearings[next].t <= traj.t[k]; ++next)
        {
            const auto& b = bearings[next];
            mrpt::math::TPose2D robot;
            if (!b.hasAoa || !traj.interpolate(b.t, robot, 1e9)) continue;
            const double x = robot.x + 0.1 * std::cos(robot.phi);
            const double y = robot.y + 0.1 * std::sin(robot.phi);
            const auto* ap = aps.find(b.transmitter);
            ASSERT_NE(ap, nullptr);
            const double len = std::hypot(ap->pose.x - x, ap->pose.y - y);
            const double a = robot.phi + b.aoa;
            points += std::string(points.empty() ? "" : ",") + point(x, y) + "," +
                      point(x + len * std::cos(a), y + len * std::sin(a));
            ++rays;
        }
        if (!points.empty())
            add("/bearing_rays", traj.t[k],
                "{\"markers\":[{\"header\":" + std::string(kMapHeader) +
                    ",\"ns\":\"bearing_rays\",\"id\":0,\"type\":5,\"action\":0,\"points\":[" +
                    points + "]}]}");
    }
    add("/path", traj.t.back(),
        "{\"header\":" + std::string(kMapHeader) + ",\"poses\":[" + pathPoses + "]}");
    EXPECT_GT(rays, 100u);

    std::string channels;
    for (const auto& [topic, type] : std::vector<std::pair<std::string, std::string>>{
             {"/transmitters", "visualization_msgs/msg/MarkerArray"},
             {"/pose", "geometry_msgs/msg/PoseStamped"},
             {"/tf", "tf2_msgs/msg/TFMessage"},
             {"/bearing_rays", "visualization_msgs/msg/MarkerArray"},
             {"/path", "nav_msgs/msg/Path"}})
        channels += std::string(channels.empty() ? "" : ",") + "{\"topic\":\"" + topic +
                    "\",\"schema\":\"" + type +
                    "\",\"messageEncoding\":\"cdr\",\"metadataKeys\":[\"offered_qos_profiles\"]}";
    std::string all;
    for (size_t i = 0; i < msgs.size(); ++i) all += (i ? "," : "") + msgs[i];
    // The text output rounds positions to 1 µm, quaternions to 1e-9 and times to 1 µs.
    std::ofstream(tmp.file("expected.json"))
        << "{\"profile\":\"ros2\",\"compression\":\"zstd\",\"tolerance\":2e-6,"
           "\"timeToleranceNs\":1000,\"schemas\":{"
           "\"geometry_msgs/msg/PoseStamped\":[\"header:Header\",\"pose:Pose\"],"
           "\"tf2_msgs/msg/TFMessage\":[\"transforms:TransformStamped[]\"],"
           "\"nav_msgs/msg/Path\":[\"header:Header\",\"poses:PoseStamped[]\"],"
           "\"visualization_msgs/msg/MarkerArray\":[\"markers:Marker[]\"]},"
           "\"channels\":["
        << channels << "],\"messages\":[" << all << "]}";
    const auto check = test::run(
        "NODE_PATH=" + npmTools() + "/node_modules node " + test::sourceDir() +
        "/tests/sensor/mcap_check.mjs " + mcap + " " + tmp.file("expected.json"));
    EXPECT_EQ(check.exitCode, 0) << check.output;
    std::cout << check.output;
}
