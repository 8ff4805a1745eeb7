/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>

#include <string>
#include <vector>

namespace mrpt_wifi::localization
{
/** What a rawlog holds for the localization apps. */
struct RawlogContents
{
    std::vector<BearingRecord> bearings;  //!< from CObservationWiFiBearing
    Trajectory2D odometry;                //!< from CObservationOdometry (accumulated pose)
    size_t otherObservations = 0;         //!< CSI and anything else, skipped
};

/** Reads a rawlog (observation-only or action/sensory-frame format). */
RawlogContents readRawlog(const std::string& path);

/** A bearing observation from a record (sensor label "WIFI_BEARING", algorithm `algorithm`).
 *  The CSV carries no channel: the observation's chanspec is a placeholder (5 GHz 155/80). */
CObservationWiFiBearing::Ptr observationFromRecord(
    const BearingRecord& r, const std::string& algorithm = "external");

/** Writes an observation-only rawlog for pf-localization: odometry readings and bearings merged
 *  by time. Returns the number of observations written. */
size_t writePfRawlog(
    const std::string& path, const std::vector<BearingRecord>& bearings,
    const Trajectory2D& odometry);

/** Writes an action/sensory-frame rawlog for pf-localization without odometry: one sensory frame
 *  per bearing time (bearings with the same timestamp share it), each after the action `motion`
 *  gives for the time since the previous frame (zero mean; with a heavy-tailed `motion`, the
 *  Gaussian of its wide part). Returns the number of sensory frames. */
size_t writePfRawlogUnknownMotion(
    const std::string& path, const std::vector<BearingRecord>& bearings,
    const UnknownMotion& motion);

}  // namespace mrpt_wifi::localization
