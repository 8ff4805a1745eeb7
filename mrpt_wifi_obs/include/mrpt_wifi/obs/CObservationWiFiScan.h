/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <string>
#include <vector>

namespace mrpt_wifi
{
/** One access point seen by a scan. */
struct ScannedAccessPoint
{
    MacAddress bssid;
    std::string ssid;
    Chanspec chanspec;  //!< the AP's operating channel and bandwidth
    int rssi_dBm = -127;
    int noise_dBm = 0;  //!< 0 when the scanner doesn't report it

    bool operator==(const ScannedAccessPoint& o) const
    {
        return bssid == o.bssid && ssid == o.ssid && chanspec == o.chanspec &&
               rssi_dBm == o.rssi_dBm && noise_dBm == o.noise_dBm;
    }
};

/** The result of one access-point scan (router-side `wl scan`, or the host's `iw`),
 *  recorded in the rawlog beside the CSI so channel decisions can be replayed. */
class CObservationWiFiScan : public mrpt::obs::CObservation
{
    DEFINE_SERIALIZABLE(CObservationWiFiScan, mrpt_wifi)

public:
    mrpt::poses::CPose3D sensorPose;
    std::string scanner;  //!< "router" or "host", plus the interface, e.g. "router:eth6"
    std::vector<ScannedAccessPoint> accessPoints;

    /** The strongest AP in a band (5 GHz by default); nullptr if none. */
    const ScannedAccessPoint* strongest(WifiBand band = WifiBand::Band5G) const;

    void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
    void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }
    void getDescriptionAsText(std::ostream& o) const override;
    bool exportTxtSupported() const override { return true; }
    std::string exportTxtHeader() const override;
    std::string exportTxtDataRow() const override;
};

}  // namespace mrpt_wifi
