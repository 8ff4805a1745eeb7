/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/BoundedArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>

#include <algorithm>
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
/** Bound on the alternatives a stored observation may hold beyond the first (corrupt input
 *  must not allocate without limit). */
constexpr size_t kMaxStoredAlternatives = 15;
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
    return 2;
}

std::vector<CObservationWiFiBearing::AoaAlternative> CObservationWiFiBearing::aoaAlternatives()
    const
{
    std::vector<AoaAlternative> all;
    if (!hasAoaAlternative) return all;
    all.push_back({aoaAlternative_rad, aoaAlternativeWeight});
    all.insert(all.end(), moreAoaAlternatives.begin(), moreAoaAlternatives.end());
    return all;
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
    const auto& more = hasAoaAlternative ? moreAoaAlternatives : std::vector<AoaAlternative>();
    out << uint8_t(std::min<size_t>(more.size(), kMaxStoredAlternatives));
    for (size_t i = 0; i < more.size() && i < kMaxStoredAlternatives; ++i)
        out << more[i].aoa_rad << more[i].weight;
}

void CObservationWiFiBearing::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
    switch (version)
    {
        case 0:
        case 1:
        case 2:
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
            moreAoaAlternatives.clear();
            if (version >= 2)
            {
                uint8_t n = 0;
                in >> n;
                if (n > kMaxStoredAlternatives || (n > 0 && !hasAoaAlternative))
                    THROW_EXCEPTION_FMT(
                        "CObservationWiFiBearing: %u more AoA alternatives stored (at most %u, "
                        "and only after a first one)",
                        unsigned(n), unsigned(kMaxStoredAlternatives));
                moreAoaAlternatives.resize(n);
                for (auto& a : moreAoaAlternatives)
                {
                    in >> a.aoa_rad >> a.weight;
                    if (!std::isfinite(a.aoa_rad) || !(a.weight >= 0 && a.weight <= 1))
                        THROW_EXCEPTION(
                            "CObservationWiFiBearing: a stored AoA alternative has a non-finite "
                            "angle or a weight outside [0, 1]");
                }
            }
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
    {
        for (const auto& a : aoaAlternatives())
            o << "  AoA alternative : " << deg(a.aoa_rad) << " deg  (weight " << a.weight
              << ": probability it, not the AoA, is the transmitter's)\n";
        o << "  AoA direction sigma: " << deg(aoaDirectionStd_rad)
          << " deg (each direction's, given it is the right one)\n";
    }
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
           "HAS_AOA_ALT AOA_ALT_RAD AOA_ALT_WEIGHT AOA_DIRECTION_STD_RAD AOA_ALT2_RAD "
           "AOA_ALT2_WEIGHT "
           "AOA_ALT3_RAD AOA_ALT3_WEIGHT";
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
    // Fixed columns: the second and third alternatives (0 0 when absent).
    for (size_t i = 0; i < 2; ++i)
    {
        const bool has = hasAoaAlternative && i < moreAoaAlternatives.size();
        o << " " << (has ? moreAoaAlternatives[i].aoa_rad : 0.0) << " "
          << (has ? moreAoaAlternatives[i].weight : 0.0);
    }
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
