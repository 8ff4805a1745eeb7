/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt_wifi/calib/PoseTrack.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi::calib
{
/** A transmitter at a known position (the frame the robot poses are in). */
struct TransmitterSite
{
    std::string name;
    std::optional<MacAddress> mac;  //!< nullopt: whatever transmitter the frames come from
    mrpt::math::TPoint2D position;
    /** Boresight of the transmitter's array [rad] (`yaw_deg`), and the array (`array: FILE`,
     *  relative to the list, or `array_elements: [[x, y], ...]` as wifi-sim writes): needed to
     *  calibrate its transmit chains. */
    std::optional<double> yaw_rad;
    std::optional<AntennaArray> array;
};

/** Reads a list of transmitters: a YAML map with `transmitters:` listing `name` (optional),
 *  `mac`, `position: [x, y]` (metres) and, for the transmit chains, `yaw_deg` and `array` or
 *  `array_elements`; other keys are ignored, so the `transmitters.yaml`
 *  that `wifi-sim --truth-dir` writes can be used directly. Throws std::runtime_error naming
 *  the file and entry. */
std::vector<TransmitterSite> loadTransmitterSites(const std::string& path);

/** What a first, cheap pass over a rawlog found: enough to reject bad input before any work. */
struct RawlogSummary
{
    struct Source
    {
        uint64_t frames = 0;
        std::map<std::string, uint64_t> channels;  //!< chanspec text → frames
        unsigned maxRx = 0;
        /** Receive cores of the rows of its widest frame (CObservationWiFiCSI::rxCores; empty:
         *  row i is core i). */
        std::vector<uint8_t> rxCores;
        int minRssi = 127, maxRssi = -128;
    };
    uint64_t csiFrames = 0;
    uint64_t odometryReadings = 0;
    std::map<MacAddress, Source> transmitters;
    PoseTrack odometry;  //!< poses of the CObservationOdometry readings (odometry frame)
    double firstCsiTime = 0, lastCsiTime = 0;
};

/** Calls `onCsi` for every CObservationWiFiCSI and `onOdometry` (time, pose) for every
 *  CObservationOdometry of a rawlog, in file order; both rawlog formats (observations only, or
 *  sensory frames + actions) are read. `onProgress` gets the fraction of the file read.
 *  Throws std::runtime_error if the file can't be opened. */
void readRawlog(
    const std::string& path, const std::function<void(const CObservationWiFiCSI&)>& onCsi,
    const std::function<void(double, const mrpt::math::TPose2D&)>& onOdometry,
    const std::function<void(double)>& onProgress = {});

/** The first pass: counts frames per transmitter and channel, collects the odometry. */
RawlogSummary summarizeRawlog(
    const std::string& path, const std::function<void(double)>& onProgress = {});

}  // namespace mrpt_wifi::calib
