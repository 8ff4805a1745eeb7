/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/BoundedArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiScan.h>

#include <iomanip>
#include <sstream>

using namespace mrpt_wifi;

IMPLEMENTS_SERIALIZABLE(CObservationWiFiScan, mrpt::obs::CObservation, mrpt_wifi)

const ScannedAccessPoint* CObservationWiFiScan::strongest(WifiBand band) const
{
    const ScannedAccessPoint* best = nullptr;
    for (const auto& ap : accessPoints)
        if (ap.chanspec.band == band && (!best || ap.rssi_dBm > best->rssi_dBm)) best = &ap;
    return best;
}

uint8_t CObservationWiFiScan::serializeGetVersion() const
{
    return 0;
}

void CObservationWiFiScan::serializeTo(mrpt::serialization::CArchive& out) const
{
    out << timestamp << sensorLabel << sensorPose << scanner;
    out.WriteAs<uint32_t>(accessPoints.size());
    for (const auto& ap : accessPoints)
    {
        out.WriteBuffer(ap.bssid.bytes.data(), ap.bssid.bytes.size());
        out << ap.ssid << ap.chanspec.raw;
        out.WriteAs<int16_t>(ap.rssi_dBm);
        out.WriteAs<int16_t>(ap.noise_dBm);
    }
}

void CObservationWiFiScan::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
    switch (version)
    {
        case 0:
        {
            constexpr const char* kWhat = "CObservationWiFiScan";
            in >> timestamp;
            readBoundedString(in, sensorLabel, kMaxStoredStringLength, kWhat);
            in >> sensorPose;
            readBoundedString(in, scanner, kMaxStoredStringLength, kWhat);
            const auto n = in.ReadAs<uint32_t>();
            accessPoints.clear();
            accessPoints.reserve(std::min<uint32_t>(n, 4096));
            for (uint32_t i = 0; i < n; ++i)
            {
                ScannedAccessPoint ap;
                in.ReadBuffer(ap.bssid.bytes.data(), ap.bssid.bytes.size());
                uint16_t raw = 0;
                readBoundedString(in, ap.ssid, kMaxStoredStringLength, kWhat);
                in >> raw;
                const auto cs = Chanspec::decode(raw);
                if (!cs)
                    THROW_EXCEPTION_FMT(
                        "CObservationWiFiScan: stored chanspec 0x%04x is invalid", raw);
                ap.chanspec = *cs;
                ap.rssi_dBm = in.ReadAs<int16_t>();
                ap.noise_dBm = in.ReadAs<int16_t>();
                accessPoints.push_back(std::move(ap));
            }
        }
        break;
        default:
            MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
    }
}

void CObservationWiFiScan::getDescriptionAsText(std::ostream& o) const
{
    CObservation::getDescriptionAsText(o);
    o << "WiFi access-point scan by " << scanner << ": " << accessPoints.size() << " APs\n";
    o << "  BSSID              RSSI[dBm]  Channel   SSID\n";
    for (const auto& ap : accessPoints)
        o << "  " << ap.bssid.asString() << "  " << std::setw(9) << ap.rssi_dBm << "  " << std::left
          << std::setw(8) << ap.chanspec.asString() << std::right << "  \"" << ap.ssid << "\"\n";
}

std::string CObservationWiFiScan::exportTxtHeader() const
{
    return "%  N_APS  [BSSID_HI24 BSSID_LO24 RSSI_DBM CHANNEL BW_MHZ] x N_APS";
}

std::string CObservationWiFiScan::exportTxtDataRow() const
{
    std::ostringstream o;
    o << accessPoints.size();
    for (const auto& ap : accessPoints)
    {
        const uint64_t mac = ap.bssid.asUint64();
        o << " " << (mac >> 24) << " " << (mac & 0xFFFFFF) << " " << ap.rssi_dBm << " "
          << int(ap.chanspec.centerChannel) << " " << ap.chanspec.bandwidthMHz;
    }
    return o.str();
}
