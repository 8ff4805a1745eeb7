/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/calib/PhaseCalibrator.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <cmath>
#include <sstream>
#include <string>

namespace calibtest
{
/** A drive near one transmitter, as scenario text for the simulator. */
struct DriveSpec
{
    std::string channel = "155/80";
    uint32_t seed = 11;  //!< the receiver hardware (phase offsets) is a function of the seed
    double duration_s = 60;
    std::string motion = "random_walk";  //!< or "static"
    double startX = 9.5, startY = 5.0, startYaw_deg = 180;
    double centerX = 7.0, centerY = 5.0, radius_m = 3.5;
    double txX = 7.0, txY = 5.0;
    bool multipath = true;  //!< room walls |Γ| = 0.35 and two scatterers
    bool blockLos = false;  //!< a box of 25 dB obstacles around the transmitter
    double snr_dB = 20;
    /** All four receive elements at (practically) one point: every antenna sees the same
     *  signal, as with a splitter and equal cables (the simulator refuses exact duplicates). */
    bool splitter = false;
    double frameRate_Hz = 100;
    bool odometry = false;  //!< CObservationOdometry in the stream (starts at the origin)
    /** Receiver array file under share/arrays and its CSI format (receiver.csi_format). */
    std::string array = "rt-ac86u";
    std::string csiFormat = "nexmon";
};

inline std::string scenarioText(const DriveSpec& d)
{
    std::ostringstream s;
    s << "name: calibtest\nduration_s: " << d.duration_s << "\nseed: " << d.seed << "\n";
    if (d.multipath)
        s << "room:\n  corners: [[0, 0], [14, 0], [14, 10], [0, 10]]\n"
             "  reflection: {magnitude: 0.35, phase_deg: 180}\n"
             "scatterers:\n  - {name: pillar, position: [4.0, 7.5], rcs_m2: 0.8}\n"
             "  - {name: machine, position: [11.0, 2.5], rcs_m2: 1.5, phase_deg: 40}\n";
    if (d.blockLos)
    {
        // A U of 30 dB absorbers around the transmitter, open towards +x only: the robot
        // (driving on the −x side) gets no line of sight, only reflections that left through
        // the opening and came back from the walls.
        const double r = 0.4, x = d.txX, y = d.txY;
        s << "obstacles:\n";
        const double c[3][4] = {
            {x + r, y - r, x - r, y - r},
            {x - r, y - r, x - r, y + r},
            {x - r, y + r, x + r, y + r}};
        for (int i = 0; i < 3; ++i)
            s << "  - {from: [" << c[i][0] << ", " << c[i][1] << "], to: [" << c[i][2] << ", "
              << c[i][3] << "], attenuation_db: 30}\n";
    }
    s << "transmitters:\n  - name: ap0\n    mac: '02:11:22:33:44:01'\n    position: [" << d.txX
      << ", " << d.txY << "]\n    channel: " << d.channel
      << "\n    frame_rate_hz: " << d.frameRate_Hz << "\n";
    s << "receiver:\n  array: "
      << (d.splitter ? "{name: splitter, elements: [[0, 0], [0, 1e-6], [0, 2e-6], [0, 3e-6]]}"
                     : std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/" + d.array + ".yaml")
      << "\n  csi_format: " << d.csiFormat
      << "\n  sensor_pose: {x: 0.1, y: 0.0, z: 0.4, yaw_deg: 0}\n";
    s << "motion:\n  type: " << d.motion << "\n  start: [" << d.startX << ", " << d.startY << ", "
      << d.startYaw_deg << "]\n";
    if (d.motion == "random_walk")
        s << "  center: [" << d.centerX << ", " << d.centerY << "]\n  radius_m: " << d.radius_m
          << "\n  speed_mps: 0.5\n  turn_rate_dps: 60\n";
    s << "odometry:\n  enabled: " << (d.odometry ? "true" : "false") << "\n";
    s << "impairments:\n  snr_db: " << d.snr_dB << "\n  ripple_deg: 5\n";
    return s.str();
}

inline mrpt_wifi::sim::Scenario scenario(const DriveSpec& d)
{
    return mrpt_wifi::sim::Scenario::fromYamlText(
        scenarioText(d), "calibtest", std::string(MRPT_WIFI_SOURCE_DIR) + "/share/scenarios");
}

inline mrpt_wifi::AntennaArray rtac86u()
{
    return mrpt_wifi::AntennaArray::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/rt-ac86u.yaml");
}

inline mrpt_wifi::AntennaArray arrayOf(const DriveSpec& d)
{
    return mrpt_wifi::AntennaArray::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/" + d.array + ".yaml");
}

/** Runs the simulator to its end, preparing every CSI frame with the true robot pose. Calls
 *  f(const CalibrationFrame&, const FrameTruth&) for the accepted ones. */
template <class F>
size_t driveFrames(
    mrpt_wifi::sim::Simulator& sim, mrpt_wifi::calib::FramePreparer& prep, bool splitter, F&& f)
{
    sim.setOdometryEnabled(false);
    mrpt_wifi::sim::SimEvent ev;
    mrpt_wifi::calib::CalibrationFrame frame;
    const auto tx = sim.scenario().transmitters.at(0).pose;
    size_t n = 0;
    while (sim.next(ev))
    {
        if (ev.kind != mrpt_wifi::sim::SimEvent::Kind::Csi) continue;
        const auto r = splitter ? prep.prepareStatic(*ev.csi, frame)
                                : prep.prepare(*ev.csi, ev.frame.robotPose, {tx.x, tx.y}, frame);
        if (r != mrpt_wifi::RejectReason::Accepted) continue;
        f(frame, ev.frame);
        ++n;
    }
    return n;
}

/** RMS [deg] over antennas 1.. and the calibration's subcarriers of the difference between the
 *  recovered phases and the simulator's true ones (relative to antenna 0). */
inline double phaseErrorRms_deg(
    const mrpt_wifi::PhaseCalibration& c, const mrpt_wifi::sim::HardwareModel& hw)
{
    const unsigned nfft = c.chanspec.nfft();
    double acc = 0;
    size_t cnt = 0;
    for (size_t i = 1; i < c.antennas(); ++i)
        for (size_t j = 0; j < c.subcarriers.size(); ++j)
        {
            const int k = c.subcarriers[j];
            const double truth = hw.chain(c.chanspec, unsigned(i)).phase_rad(k, nfft) -
                                 hw.chain(c.chanspec, 0).phase_rad(k, nfft);
            const double e = mrpt_wifi::wrapAngle(c.phases_rad[i][j] - truth);
            acc += e * e;
            ++cnt;
        }
    return std::sqrt(acc / double(cnt)) * 180 / M_PI;
}

}  // namespace calibtest
