/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationBearingRange.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <string>
#include <vector>

namespace mrpt_wifi
{
/** The bearing of one WiFi transmitter estimated from CSI: angle of arrival at the robot's
 *  array and, when the transmitter sends several streams from a known array, angle of departure
 *  at the transmitter. Angles in radians (MRPT convention, counter-clockwise):
 *  AoA in the receive array's frame (its pose on the robot is `sensorPose`), AoD in the
 *  transmitter array's frame (DESIGN.md §6).
 *
 * Linear arrays cannot tell an angle from its mirror across the array axis: then `aoaAmbiguous`
 * is set and `aoaMirror_rad` holds the other candidate, equally consistent with the CSI
 * (`aoa_rad` is the one in the array's front half-plane, not a better guess). Same for AoD.
 *
 * A window whose profile also supports other directions (a reflection stronger than the
 * direct path; near endfire the rt-ac86u's 26 mm spacing aliasing the other endfire) has
 * `hasAoaAlternative`: `aoaAlternative_rad` (folded as aoa_rad, its mirror the array's mirror of
 * it) is the heaviest alternative, `moreAoaAlternatives` the others (at most
 * bearing::kMaxAoaAlternatives in all, heaviest first). A weight (0..1) is the probability that
 * that direction and not aoa_rad is the transmitter's (bearing::AoaAlternative); aoa_rad keeps
 * 1 − their sum. `aoaStd_rad` reaches the strongest ambiguous one; `aoaDirectionStd_rad` is the
 * σ of each direction, given it is the right one: a consumer may weigh the directions as a
 * mixture with that σ instead of one wide σ. Without an alternative it equals aoaStd_rad.
 * The first alternative is stored since serialization version 1, the others since version 2
 * (older rawlogs read as none). */
class CObservationWiFiBearing : public mrpt::obs::CObservation
{
    DEFINE_SERIALIZABLE(CObservationWiFiBearing, mrpt_wifi)

public:
    /** Pose of the receive array on the robot. */
    mrpt::poses::CPose3D sensorPose;
    MacAddress transmitter;
    Chanspec chanspec;
    int8_t rssi_dBm = 0;
    std::string algorithm;      //!< estimator name ("aoa_only", "spotfi", ...)
    uint16_t framesUsed = 0;    //!< CSI frames combined
    uint8_t pathsDetected = 0;  //!< signal-subspace dimension / peaks considered

    double aoa_rad = 0;
    double aoaStd_rad = 0;
    bool aoaAmbiguous = false;
    double aoaMirror_rad = 0;
    bool hasAoaAlternative = false;
    double aoaAlternative_rad = 0;
    double aoaAlternativeWeight = 0;
    double aoaDirectionStd_rad = 0;
    /** One more direction: angle (folded as aoa_rad) and weight. */
    struct AoaAlternative
    {
        double aoa_rad = 0;
        double weight = 0;
    };
    std::vector<AoaAlternative> moreAoaAlternatives;  //!< second and later, heaviest first
    /** All alternatives, the first from the scalar fields (empty without). */
    std::vector<AoaAlternative> aoaAlternatives() const;

    bool hasAod = false;
    double aod_rad = 0;
    double aodStd_rad = 0;
    bool aodAmbiguous = false;
    double aodMirror_rad = 0;

    bool hasDelay = false;
    double delay_s = 0;  //!< chosen path's delay relative to the frame's mean delay
    double quality = 0;  //!< 0..1, see bearing::BearingResult::quality

    /** A landmark ID for MRPT tools: the low 30 bits of the MAC (as an integer). */
    static int32_t landmarkIdOf(const MacAddress& mac);
    /** ID of the mirror candidate: landmarkIdOf(mac) + 2^30 (MRPT forbids duplicate IDs in
     *  one CObservationBearingRange). */
    static int32_t mirrorLandmarkIdOf(const MacAddress& mac);

    /** The AoA as a CObservationBearingRange (yaw; range unknown, set to 0 with
     *  `sensor_std_range` = −1 meaning "no range"), landmark ID from the MAC. With
     *  `includeMirror` and an ambiguous AoA, the mirror candidate is a second measurement with
     *  mirrorLandmarkIdOf(). */
    mrpt::obs::CObservationBearingRange::Ptr asBearingRange(bool includeMirror = true) const;

    // CObservation interface
    void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
    void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }
    void getDescriptionAsText(std::ostream& o) const override;
    bool exportTxtSupported() const override { return true; }
    std::string exportTxtHeader() const override;
    std::string exportTxtDataRow() const override;
};

}  // namespace mrpt_wifi
