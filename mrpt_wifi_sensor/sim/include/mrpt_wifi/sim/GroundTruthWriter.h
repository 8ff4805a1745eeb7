/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/sim/Simulator.h>

#include <fstream>
#include <string>

namespace mrpt_wifi::sim
{
/** The transmitters of a scenario as `transmitters.yaml` (name, MAC, position, yaw, channel,
 * streams, frame rate, power, array elements; world frame), the file wifi-calibrate's
 * --transmitters and the scorers read. */
void writeTransmittersYaml(std::ostream& o, const Scenario& sc);

/** Writes the ground truth of a simulation into a folder:
 *  - `trajectory_tum.txt`: robot base ground truth, TUM (`t x y z qx qy qz qw`, unix time);
 *  - `odometry_tum.txt`: the odometry as reported (its own frame), TUM;
 *  - `transmitters.yaml`: name, MAC, pose, channel, streams, array of every transmitter;
 *  - `frames.csv`: one row per CSI frame: true AoA/AoD (rad and deg), LoS delay, SNR, RSSI...;
 *  - `impairments.json`: the receiver's true phase offsets/ripple per channel and chain, jump
 *    timeline, and the settings of the per-packet draws.
 * Files are complete only after finish(). */
class GroundTruthWriter
{
public:
    /** Creates the folder if needed; throws std::runtime_error if a file can't be opened. */
    GroundTruthWriter(const std::string& dir, const Simulator& sim);
    ~GroundTruthWriter();

    void add(const SimEvent& ev);
    /** Writes the trajectory (up to `endTime_s`), transmitters and impairments; closes all. */
    void finish(double endTime_s);

    const std::string& directory() const { return dir_; }

private:
    const Simulator& sim_;
    std::string dir_;
    std::ofstream frames_, odometry_;
    bool finished_ = false;
};

}  // namespace mrpt_wifi::sim
