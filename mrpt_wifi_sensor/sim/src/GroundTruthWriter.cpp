/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/sim/GroundTruthWriter.h>

#include <cmath>
#include <iomanip>
#include <stdexcept>

namespace mrpt_wifi::sim
{
namespace
{
constexpr double kRad2Deg = 180.0 / M_PI;

std::ofstream openOrThrow(const std::string& path)
{
    std::ofstream f(path);
    if (!f) throw std::runtime_error("cannot write " + path);
    f << std::fixed;
    return f;
}

/** TUM line for a planar pose: `t x y z qx qy qz qw`. */
void writeTum(std::ostream& o, double unixTime, const mrpt::math::TPose2D& p)
{
    o << std::setprecision(6) << unixTime << " " << p.x << " " << p.y << " 0 0 0 "
      << std::setprecision(9) << std::sin(p.phi / 2) << " " << std::cos(p.phi / 2) << "\n";
}
}  // namespace

void writeTransmittersYaml(std::ostream& txs, const Scenario& sc)
{
    txs << std::fixed;
    txs << std::setprecision(6) << "# transmitters of scenario '" << sc.name
        << "' (world frame, metres; yaw in degrees)\ntransmitters:\n";
    for (const auto& t : sc.transmitters)
    {
        txs << "  - name: " << t.name << "\n    mac: '" << t.mac.asString() << "'\n"
            << "    position: [" << t.pose.x << ", " << t.pose.y << "]\n"
            << "    yaw_deg: " << t.pose.phi * kRad2Deg << "\n"
            << "    channel: " << t.chanspec.asString() << "\n"
            << "    streams: " << t.streams << "\n"
            << "    frame_rate_hz: " << t.frameRate_Hz << "\n"
            << "    tx_power_dbm: " << t.txPower_dBm << "\n"
            << "    array_elements: [";
        for (size_t i = 0; i < t.array.size(); ++i)
            txs << (i ? ", " : "") << "[" << t.array.elements[i].x << ", " << t.array.elements[i].y
                << "]";
        txs << "]\n";
    }
}

GroundTruthWriter::GroundTruthWriter(const std::string& dir, const Simulator& sim)
    : sim_(sim), dir_(dir)
{
    if (!mrpt::system::directoryExists(dir_) && !mrpt::system::createDirectory(dir_))
        throw std::runtime_error("cannot create the ground-truth folder " + dir_);
    frames_ = openOrThrow(dir_ + "/frames.csv");
    frames_ << "timestamp_unix,t_s,transmitter,mac,seq,chanspec,robot_x,robot_y,robot_yaw_rad,"
               "sensor_x,sensor_y,sensor_yaw_rad,aoa_rad,aoa_deg,aod_rad,aod_deg,los_distance_m,"
               "los_delay_ns,los_loss_db,k_factor_db,strongest_aoa_rad,n_paths,rx_power_dbm,"
               "snr_db,rssi_dbm,sto_ns,cfo_phase_rad,agc_gain_db,jump_states\n";
    odometry_ = openOrThrow(dir_ + "/odometry_tum.txt");
    odometry_ << "# odometry as reported (odometry frame), TUM: t x y z qx qy qz qw\n";
}

GroundTruthWriter::~GroundTruthWriter()
{
    if (!finished_)
    {
        try
        {
            finish(sim_.duration());
        }
        catch (...)
        {
        }
    }
}

void GroundTruthWriter::add(const SimEvent& ev)
{
    const double unixTime = sim_.scenario().startTime_unix + ev.time_s;
    if (ev.kind == SimEvent::Kind::Odometry)
    {
        writeTum(odometry_, unixTime, ev.odometry->odometry.asTPose());
        return;
    }
    const FrameTruth& f = ev.frame;
    const auto& tx = sim_.scenario().transmitters[f.transmitterIndex];
    const unsigned nRx = unsigned(sim_.scenario().receiver.array.size());
    auto& o = frames_;
    o << std::setprecision(6) << unixTime << "," << ev.time_s << "," << tx.name << ","
      << tx.mac.asString() << "," << f.sequenceNumber << "," << tx.chanspec.asString() << ","
      << f.robotPose.x << "," << f.robotPose.y << "," << f.robotPose.phi << "," << f.sensorPose.x
      << "," << f.sensorPose.y << "," << f.sensorPose.phi << "," << f.aoa_rad << ","
      << f.aoa_rad * kRad2Deg << "," << f.aod_rad << "," << f.aod_rad * kRad2Deg << ","
      << f.losDistance_m << "," << f.losDelay_s * 1e9 << "," << f.losCrossingLoss_dB << ","
      << f.kFactor_dB << "," << f.strongestPathAoa_rad << "," << f.pathCount << "," << f.rxPower_dBm
      << "," << f.snr_dB << "," << int(f.rssi_dBm) << "," << f.packet.samplingTimeOffset_s * 1e9
      << "," << f.packet.cfoPhase_rad << "," << f.packet.agcGain_dB << ",";
    for (unsigned i = 0; i < nRx; ++i) o << (i ? "|" : "") << int(f.packet.jumpState[i]);
    o << "\n";
}

void GroundTruthWriter::finish(double endTime_s)
{
    if (finished_) return;
    finished_ = true;
    const Scenario& sc = sim_.scenario();

    auto traj = openOrThrow(dir_ + "/trajectory_tum.txt");
    traj << "# ground truth of the robot base (world frame), TUM: t x y z qx qy qz qw\n";
    const double step = std::max(sim_.trajectory().timeStep(), 0.01);
    const double end = std::min(endTime_s, sim_.duration());
    for (size_t i = 0; double(i) * step <= end + 1e-9; ++i)
        writeTum(
            traj, sc.startTime_unix + double(i) * step, sim_.trajectory().poseAt(double(i) * step));

    auto txs = openOrThrow(dir_ + "/transmitters.yaml");
    writeTransmittersYaml(txs, sc);

    auto imp = openOrThrow(dir_ + "/impairments.json");
    imp.unsetf(std::ios::fixed);
    sim_.writeImpairmentsJson(imp);

    frames_.close();
    odometry_.close();
    if (!frames_ || !odometry_ || !traj || !txs || !imp)
        throw std::runtime_error("error writing the ground truth into " + dir_);
}

}  // namespace mrpt_wifi::sim
