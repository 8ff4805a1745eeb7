/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/format.h>
#include <mrpt_wifi/sensor/AccessPointSelector.h>

#include <algorithm>

namespace mrpt_wifi
{
std::optional<AccessPointSelector::Decision> AccessPointSelector::onScan(
    const CObservationWiFiScan& scan, double t_s)
{
    const ScannedAccessPoint* best = nullptr;
    const ScannedAccessPoint* current = nullptr;
    for (const auto& ap : scan.accessPoints)
    {
        if (ap.chanspec.band != options_.band) continue;
        if (!options_.ssidFilter.empty() && ap.ssid != options_.ssidFilter) continue;
        if (locked_ && ap.bssid == locked_->bssid) current = &ap;
        if (ap.rssi_dBm >= options_.minRssi_dBm && (!best || ap.rssi_dBm > best->rssi_dBm))
            best = &ap;
    }

    const auto lockOnto = [&](const ScannedAccessPoint& ap, std::string reason)
    {
        const bool retune =
            !locked_ || locked_->chanspec != ap.chanspec || locked_->bssid != ap.bssid;
        locked_ = ap;
        lockTime_s_ = t_s;
        missingScans_ = 0;
        return retune ? std::optional<Decision>(Decision{ap, std::move(reason)}) : std::nullopt;
    };

    if (!locked_)
    {
        if (!best) return std::nullopt;
        return lockOnto(
            *best, mrpt::format(
                       "initial lock: %s \"%s\" at %d dBm on %s", best->bssid.asString().c_str(),
                       best->ssid.c_str(), best->rssi_dBm, best->chanspec.asString().c_str()));
    }
    if (!current)
    {
        if (++missingScans_ < options_.missingScansToDrop || !best) return std::nullopt;
        const std::string lost = locked_->bssid.asString();
        return lockOnto(
            *best, mrpt::format(
                       "%s missing from %u scans: lock %s \"%s\" at %d dBm on %s", lost.c_str(),
                       missingScans_, best->bssid.asString().c_str(), best->ssid.c_str(),
                       best->rssi_dBm, best->chanspec.asString().c_str()));
    }
    missingScans_ = 0;
    locked_->rssi_dBm = current->rssi_dBm;
    if (!best || best->bssid == locked_->bssid) return std::nullopt;
    const double gain = best->rssi_dBm - current->rssi_dBm;
    const double dwell = t_s - lockTime_s_;
    if (gain < options_.minRssiGain_dB || dwell < options_.minDwell_s) return std::nullopt;
    return lockOnto(
        *best,
        mrpt::format(
            "%s \"%s\" at %d dBm beats locked %s at %d dBm by %.0f dB (>= %.0f) after "
            "%.1f s (>= %.1f): switch to %s",
            best->bssid.asString().c_str(), best->ssid.c_str(), best->rssi_dBm,
            current->bssid.asString().c_str(), current->rssi_dBm, gain, options_.minRssiGain_dB,
            dwell, options_.minDwell_s, best->chanspec.asString().c_str()));
}

std::vector<Chanspec> channelsFromScan(
    const CObservationWiFiScan& scan, const AccessPointSelectorOptions& options)
{
    std::vector<Chanspec> out;
    for (const auto& ap : scan.accessPoints)
    {
        if (ap.chanspec.band != options.band || ap.rssi_dBm < options.minRssi_dBm) continue;
        if (!options.ssidFilter.empty() && ap.ssid != options.ssidFilter) continue;
        if (std::none_of(
                out.begin(), out.end(),
                [&](const Chanspec& c) { return c.sameChannel(ap.chanspec); }))
            out.push_back(ap.chanspec);
    }
    std::sort(
        out.begin(), out.end(),
        [](const Chanspec& a, const Chanspec& b)
        {
            return std::make_pair(a.centerChannel, a.bandwidthMHz) <
                   std::make_pair(b.centerChannel, b.bandwidthMHz);
        });
    return out;
}

}  // namespace mrpt_wifi
