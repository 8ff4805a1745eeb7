/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiScan.h>

#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi
{
struct AccessPointSelectorOptions
{
    WifiBand band = WifiBand::Band5G;
    int minRssi_dBm = -85;  //!< weaker APs are never chosen
    /** A challenger must beat the locked AP by this much... */
    double minRssiGain_dB = 6.0;
    /** ...and the lock must be at least this old (no back-and-forth on noisy scans). */
    double minDwell_s = 10.0;
    /** Scans in a row the locked AP may be missing before the lock is dropped. */
    unsigned missingScansToDrop = 2;
    std::string ssidFilter;  //!< only APs with this SSID (empty: any)
};

/** Automatic channel mode: locks onto the nearest (strongest) access point with hysteresis,
 * unlike WiROS, which jumps to whatever was strongest in the last scan. */
class AccessPointSelector
{
public:
    struct Decision
    {
        ScannedAccessPoint target;
        std::string reason;  //!< one line, for the log
    };

    explicit AccessPointSelector(AccessPointSelectorOptions options = {}) : options_(options) {}

    /** Feeds a scan taken at `t_s` (seconds, any origin); returns a switch to make, if any. */
    std::optional<Decision> onScan(const CObservationWiFiScan& scan, double t_s);
    const std::optional<ScannedAccessPoint>& locked() const { return locked_; }

private:
    AccessPointSelectorOptions options_;
    std::optional<ScannedAccessPoint> locked_;
    double lockTime_s_ = 0;
    unsigned missingScans_ = 0;
};

/** `channel_schedule = scan`: the distinct channels of the access points in a scan that pass
 *  the band, SSID and RSSI limits of `options`, ordered by channel number (a stable visiting
 *  order from one scan to the next). */
std::vector<Chanspec> channelsFromScan(
    const CObservationWiFiScan& scan, const AccessPointSelectorOptions& options);

}  // namespace mrpt_wifi
