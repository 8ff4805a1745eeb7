/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <iosfwd>
#include <string>
#include <vector>

namespace mrpt_wifi
{
class CObservationWiFiBearing;
}

namespace mrpt_wifi::localization
{
/** One bearing measurement of one transmitter, whatever produced it (csi-bearings, another CSI
 *  tool, a simulator). Angles in radians: AoA in the robot's receive-array frame, AoD in the
 *  transmitter's array frame (DESIGN.md §6). For linear arrays, `*Ambiguous` says the mirror
 *  candidate is as likely as the reported angle. */
struct BearingRecord
{
    double t = 0;  //!< UNIX time [s]
    MacAddress transmitter;

    bool hasAoa = false;
    double aoa = 0, aoaStd = 0;
    bool aoaAmbiguous = false;
    double aoaMirror = 0;
    /** Other directions the window supports (CObservationWiFiBearing's alternatives): the
     *  heaviest in aoaAlternative, the others in moreAoaAlternatives; a weight is the
     *  probability that that direction and not aoa is the transmitter's. aoaDirectionStd is
     *  each direction's own σ (aoaStd may reach the alternative). */
    bool hasAoaAlternative = false;
    double aoaAlternative = 0, aoaAlternativeWeight = 0, aoaDirectionStd = 0;
    struct AoaAlternative
    {
        double aoa = 0, weight = 0;
    };
    std::vector<AoaAlternative> moreAoaAlternatives;  //!< second and later, heaviest first
    /** All alternatives, the first from the scalar fields (empty without). */
    std::vector<AoaAlternative> aoaAlternatives() const
    {
        std::vector<AoaAlternative> all;
        if (!hasAoaAlternative) return all;
        all.push_back({aoaAlternative, aoaAlternativeWeight});
        all.insert(all.end(), moreAoaAlternatives.begin(), moreAoaAlternatives.end());
        return all;
    }

    bool hasAod = false;
    double aod = 0, aodStd = 0;
    bool aodAmbiguous = false;
    double aodMirror = 0;

    /** Pose of the receive array on the robot (x, y, yaw) [m, rad]. */
    mrpt::math::TPose2D sensorPose{0, 0, 0};
};

/** Options for reading the bearings CSV. */
struct BearingCsvOptions
{
    double defaultStd_rad = 0.0873;           //!< σ when a row has none (5°)
    mrpt::math::TPose2D sensorPose{0, 0, 0};  //!< receive array on the robot, for every row
    /** Resolves names in the `transmitter` column; MACs are always accepted. */
    const TransmitterMap* names = nullptr;
};

/** Counted problems of an input, for summaries ("never a silent wrong answer"). */
struct InputWarnings
{
    size_t unknownTransmitter = 0;  //!< bearings of transmitters not in the map
    size_t outsideTrajectory = 0;   //!< timestamps outside the pose time span
    size_t noAngle = 0;             //!< rows with neither AoA nor AoD
    /** CSV angle cells that are filled while their `has_aoa` / `has_aod` flag is 0: ignored
     *  (the flag wins), counted because they hint at a writer that fills unmeasured cells. */
    size_t flaggedOffAngles = 0;
    std::string summary() const;
    /** The warning line a CLI prints after reading `path` ("" when there is nothing to say). */
    std::string csvWarning(const std::string& path) const;
    size_t total() const { return unknownTransmitter + outsideTrajectory + noAngle; }
};

/** Reads the bearings CSV ("bearings from elsewhere"). Format: docs in
 *  share/localization/README.md:
 *  \code
 *  # comment lines start with '#'
 *  timestamp,transmitter,aoa_deg,aoa_std_deg,aoa_mirror_deg,aod_deg,aod_std_deg,aod_mirror_deg
 *  1700000000.10,02:00:00:00:01:01,23.5,4.0,156.5,-12.0,5.0,
 *  \endcode
 *  Required columns: `timestamp` (UNIX s), `transmitter` (MAC or a name of `options.names`) and
 *  at least one of `aoa_deg` / `aod_deg`; columns may come in any order; an empty cell means "not
 *  measured"; `*_mirror_deg` non-empty marks the angle ambiguous (linear array). Optional 0/1
 *  columns `has_aoa`, `has_aod`, `aoa_ambiguous`, `aod_ambiguous` (as `csi-bearings --csv`
 *  writes them) switch the corresponding cells off when 0. Optional `aoa_alt_deg`,
 *  `aoa_alt_weight` and `aoa_direction_std_deg` (all three filled) give the AoA's alternative,
 *  `aoa_more_alts` ("deg:weight;deg:weight", after a first one) the others.
 *  Throws std::runtime_error with file:line on malformed rows and unknown transmitter names
 *  (names can't be guessed); rows without any angle are counted in `warnings`. */
std::vector<BearingRecord> readBearingCsv(
    const std::string& path, const BearingCsvOptions& options, InputWarnings* warnings = nullptr);

/** Writes records in the format above (degrees), transmitters as MACs. */
void writeBearingCsv(const std::string& path, const std::vector<BearingRecord>& records);

/** Converts a bearing observation to a record (and back). */
BearingRecord recordFromObservation(const CObservationWiFiBearing& obs);

}  // namespace mrpt_wifi::localization
