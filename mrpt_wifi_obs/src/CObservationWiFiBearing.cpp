/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/BoundedArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>

#include <cmath>
#include <iomanip>
#include <sstream>

using namespace mrpt_wifi;

IMPLEMENTS_SERIALIZABLE(CObservationWiFiBearing, mrpt::obs::CObservation, mrpt_wifi)

namespace
{
double deg(double r)
{
    return r * 180.0 / M_PI;
}
}  // namespace

int32_t CObservationWiFiBearing::landmarkIdOf(const MacAddress& mac)
{
    return int32_t(mac.asUint64() & 0x3FFFFFFFu);
}

int32_t CObservationWiFiBearing::mirrorLandmarkIdOf(const MacAddress& mac)
{
    return landmarkIdOf(mac) | 0x40000000;
}

uint8_t CObservationWiFiBearing::serializeGetVersion() const
{
    return 1;
}

void CObservationWiFiBearing::serializeTo(mrpt::serialization::CArchive& out) const
{
    out << timestamp << sensorLabel << sensorPose;
    out.WriteBuffer(transmitter.bytes.data(), transmitter.bytes.size());
    out << chanspec.raw << rssi_dBm << algorithm << framesUsed << pathsDetected;
    out << aoa_rad << aoaStd_rad << aoaAmbiguous << aoaMirror_rad;
    out << hasAod << aod_rad << aodStd_rad << aodAmbiguous << aodMirror_rad;
    out << hasDelay << delay_s << quality;
    out << hasAoaAlternative << aoaAlternative_rad << aoaAlternativeWeight << aoaDirectionStd_rad;
}

void CObservationWiFiBearing::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
    switch (version)
    {
        case 0:
        case 1:
        {
            constexpr const char* kWhat = "CObservationWiFiBearing";
            in >> timestamp;
            readBoundedString(in, sensorLabel, kMaxStoredStringLength, kWhat);
            in >> sensorPose;
            in.ReadBuffer(transmitter.bytes.data(), transmitter.bytes.size());
            uint16_t raw = 0;
            in >> raw;
            const auto cs = Chanspec::decode(raw);
            if (!cs)
                THROW_EXCEPTION_FMT(
                    "CObservationWiFiBearing: stored chanspec 0x%04x is invalid", raw);
            chanspec = *cs;
            in >> rssi_dBm;
            readBoundedString(in, algorithm, kMaxStoredStringLength, kWhat);
            in >> framesUsed >> pathsDetected;
            in >> aoa_rad >> aoaStd_rad >> aoaAmbiguous >> aoaMirror_rad;
            in >> hasAod >> aod_rad >> aodStd_rad >> aodAmbiguous >> aodMirror_rad;
            in >> hasDelay >> delay_s >> quality;
            if (version >= 1)
                in >> hasAoaAlternative >> aoaAlternative_rad >> aoaAlternativeWeight >>
                    aoaDirectionStd_rad;
            else
                hasAoaAlternative = false, aoaAlternative_rad = 0, aoaAlternativeWeight = 0,
                aoaDirectionStd_rad = aoaStd_rad;
        }
        break;
        default:
            MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
    }
}

void CObservationWiFiBearing::getDescriptionAsText(std::ostream& o) const
{
    CObservation::getDescriptionAsText(o);
    o << std::fixed << std::setprecision(2);
    o << "WiFi bearing of transmitter " << transmitter.asString() << " (landmark ID "
      << landmarkIdOf(transmitter) << ", mirror candidate " << mirrorLandmarkIdOf(transmitter)
      << ")\n";
    o << "  algorithm       : " << algorithm << " (" << framesUsed << " frame"
      << (framesUsed == 1 ? "" : "s") << ", " << int(pathsDetected) << " path(s) detected)\n";
    o << "  channel         : " << chanspec.asString() << "   RSSI: " << int(rssi_dBm) << " dBm\n";
    o << "  AoA             : " << deg(aoa_rad) << " deg  (sigma " << deg(aoaStd_rad)
      << " deg, receive array frame)\n";
    if (aoaAmbiguous)
        o << "  AoA mirror      : " << deg(aoaMirror_rad)
          << " deg  (linear array: equally consistent, not resolved)\n";
    if (hasAoaAlternative)
        o << "  AoA alternative : " << deg(aoaAlternative_rad) << " deg  (weight "
          << aoaAlternativeWeight << " of the chosen one's; sigma of each direction "
          << deg(aoaDirectionStd_rad) << " deg)\n";
    if (hasAod)
    {
        o << "  AoD             : " << deg(aod_rad) << " deg  (sigma " << deg(aodStd_rad)
          << " deg, transmitter array frame)\n";
        if (aodAmbiguous) o << "  AoD mirror      : " << deg(aodMirror_rad) << " deg\n";
    }
    else
        o << "  AoD             : not estimated\n";
    if (hasDelay) o << "  relative delay  : " << delay_s * 1e9 << " ns\n";
    o << "  quality         : " << quality << " (1 = a single clean path)\n";
    o << "  sensor pose     : " << sensorPose.asString() << "\n";
}

std::string CObservationWiFiBearing::exportTxtHeader() const
{
    return "%  MAC_HI24 MAC_LO24 CHANNEL BW_MHZ RSSI_DBM AOA_RAD AOA_STD_RAD AOA_AMBIGUOUS "
           "AOA_MIRROR_RAD HAS_AOD AOD_RAD AOD_STD_RAD AOD_MIRROR_RAD DELAY_S QUALITY FRAMES "
           "HAS_AOA_ALT AOA_ALT_RAD AOA_ALT_WEIGHT AOA_DIRECTION_STD_RAD";
}

std::string CObservationWiFiBearing::exportTxtDataRow() const
{
    std::ostringstream o;
    o << std::setprecision(9);
    const uint64_t mac = transmitter.asUint64();
    o << (mac >> 24) << " " << (mac & 0xFFFFFF) << " " << int(chanspec.centerChannel) << " "
      << chanspec.bandwidthMHz << " " << int(rssi_dBm) << " " << aoa_rad << " " << aoaStd_rad << " "
      << int(aoaAmbiguous) << " " << aoaMirror_rad << " " << int(hasAod) << " " << aod_rad << " "
      << aodStd_rad << " " << aodMirror_rad << " " << (hasDelay ? delay_s : 0.0) << " " << quality
      << " " << framesUsed << " " << int(hasAoaAlternative) << " " << aoaAlternative_rad << " "
      << aoaAlternativeWeight << " " << aoaDirectionStd_rad;
    return o.str();
}

mrpt::obs::CObservationBearingRange::Ptr CObservationWiFiBearing::asBearingRange(
    bool includeMirror) const
{
    auto obs = mrpt::obs::CObservationBearingRange::Create();
    obs->timestamp = timestamp;
    obs->sensorLabel = sensorLabel + "_BEARING";  // e.g. WIFI_CSI_AOA_BEARING
    obs->setSensorPose(sensorPose);
    obs->minSensorDistance = 0;
    obs->maxSensorDistance = 1e3f;
    obs->fieldOfView_yaw = float(2 * M_PI);
    obs->fieldOfView_pitch = 0;
    obs->validCovariances = false;
    obs->sensor_std_range = -1.f;  // no range measured
    obs->sensor_std_yaw = float(aoaStd_rad);
    obs->sensor_std_pitch = 0;
    mrpt::obs::CObservationBearingRange::TMeasurement m;
    m.range = 0;
    m.yaw = float(aoa_rad);
    m.pitch = 0;
    m.landmarkID = landmarkIdOf(transmitter);
    obs->sensedData.push_back(m);
    if (includeMirror && aoaAmbiguous)
    {
        m.yaw = float(aoaMirror_rad);
        m.landmarkID = mirrorLandmarkIdOf(transmitter);
        obs->sensedData.push_back(m);
    }
    return obs;
}
