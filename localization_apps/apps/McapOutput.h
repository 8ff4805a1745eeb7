/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// --mcap of the localization programs: their results (localization library types) as the ROS 2
// messages of ros2::LocalizationMcap (mrpt_wifi_sensor). Only the programs link both libraries.

#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/sensor/LocalizationMcap.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace mrpt_wifi::localization::mcap_output
{
using Landmarks = std::vector<ros2::LocalizationMcap::Landmark>;
using Rays = std::vector<ros2::LocalizationMcap::Ray>;

/** A ray's length when the map does not know the transmitter [m]. */
constexpr double kUnknownRayLength_m = 3.0;

/** The --mcap option's help text, the same in every program. */
inline const char* optionHelp()
{
    return "Also write the result as a ROS 2 recording (MCAP, zstd) for Foxglove: /pose, /tf, "
           "/path, /bearing_rays, /transmitters, /devices in frame 'map' (docs/programs.md)";
}

/** Transmitters (or devices) of a map; cov: (xx, xy, yy) per transmitter when known. */
inline Landmarks landmarksOf(
    const TransmitterMap& map, const std::vector<std::array<double, 3>>* cov = nullptr)
{
    Landmarks out;
    const auto& list = map.transmitters();
    for (size_t i = 0; i < list.size(); ++i)
    {
        ros2::LocalizationMcap::Landmark l;
        l.name = list[i].name.empty() ? list[i].mac.asString() : list[i].name;
        l.x = list[i].pose.x, l.y = list[i].pose.y;
        if (cov && i < cov->size()) l.cov = (*cov)[i];
        out.push_back(l);
    }
    return out;
}

/** The AoA of `b` as a ray from the receive array of the robot at `robot`: to the transmitter
 *  when `map` knows it, else kUnknownRayLength_m long. */
inline ros2::LocalizationMcap::Ray rayOf(
    const BearingRecord& b, const mrpt::math::TPose2D& robot, const TransmitterMap* map)
{
    const double c = std::cos(robot.phi), s = std::sin(robot.phi);
    ros2::LocalizationMcap::Ray r;
    r.x = robot.x + c * b.sensorPose.x - s * b.sensorPose.y;
    r.y = robot.y + s * b.sensorPose.x + c * b.sensorPose.y;
    r.angle = robot.phi + b.sensorPose.phi + b.aoa;
    r.length = kUnknownRayLength_m;
    if (const auto* t = map ? map->find(b.transmitter) : nullptr)
        r.length = std::hypot(t->pose.x - r.x, t->pose.y - r.y);
    return r;
}

/** Devices (wifi-iot-map's estimates): the localized ones, with their covariance. */
template <class DeviceList>
Landmarks devicesOf(const DeviceList& devices, TransmitterMap* asMap = nullptr)
{
    Landmarks out;
    for (const auto& d : devices)
    {
        if (!d.localized) continue;
        ros2::LocalizationMcap::Landmark l;
        l.name = d.name.empty() ? d.mac.asString() : d.name;
        l.x = d.x, l.y = d.y;
        l.cov = std::array<double, 3>{d.cov[0], d.cov[1], d.cov[2]};
        out.push_back(l);
        if (asMap && !asMap->find(d.mac))
        {
            KnownTransmitter t;
            t.mac = d.mac;
            t.name = d.mac.asString();
            t.pose = {d.x, d.y, 0};
            asMap->add(t);
        }
    }
    return out;
}

/** A whole trajectory: the transmitters first (with their covariance when given), then each pose
 * (with its covariance when given) and the rays of the AoA bearings since the previous pose (each
 * from the trajectory interpolated at its time; each as long as the distance to its transmitter in
 * rayTargets, default `transmitters`), then the devices, then the path. */
inline void writeTrajectory(
    const std::string& path, const Trajectory2D& traj,
    const std::vector<std::array<double, 9>>* poseCov, std::vector<BearingRecord> bearings,
    const TransmitterMap* transmitters, const Landmarks* devices,
    const std::vector<std::array<double, 3>>* transmitterCov = nullptr,
    const TransmitterMap* rayTargets = nullptr)
{
    if (!rayTargets) rayTargets = transmitters;
    if (traj.size() == 0) throw std::runtime_error("--mcap " + path + ": no pose to write");
    ros2::LocalizationMcap out(path, poseCov != nullptr);
    if (transmitters && transmitters->size() > 0)
        out.transmitters(traj.t.front(), landmarksOf(*transmitters, transmitterCov));
    std::stable_sort(
        bearings.begin(), bearings.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
    size_t next = 0;
    while (next < bearings.size() && bearings[next].t <= traj.t.front()) ++next;
    for (size_t k = 0; k < traj.size(); ++k)
    {
        const auto& p = traj.poses[k];
        out.pose(traj.t[k], p.x, p.y, p.phi, poseCov ? &(*poseCov)[k] : nullptr);
        Rays rays;
        for (; k > 0 && next < bearings.size() && bearings[next].t <= traj.t[k]; ++next)
        {
            mrpt::math::TPose2D robot;
            if (bearings[next].hasAoa &&
                traj.interpolate(bearings[next].t, robot, std::numeric_limits<double>::infinity()))
                rays.push_back(rayOf(bearings[next], robot, rayTargets));
        }
        if (!rays.empty()) out.bearingRays(traj.t[k], rays);
    }
    if (devices) out.devices(traj.t.back(), *devices);
    out.close();
}

}  // namespace mrpt_wifi::localization::mcap_output
