/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/bearing/BearingChainConfig.h>

#include <algorithm>
#include <stdexcept>

namespace mrpt_wifi::bearing
{
BearingChainConfig loadBearingChainConfig(const std::string& path, const std::string& algo)
{
    BearingChainConfig c;
    if (path.empty()) return c;
    const auto doc = mrpt::containers::yaml::FromFile(path);
    const auto bad = [&](const std::string& what)
    { throw std::invalid_argument("config '" + path + "': " + what); };
    for (const auto& kv : doc.asMap())
    {
        const std::string k = kv.first.as<std::string>();
        if (k != "preprocess" && k != "window" && k != "estimators" && k != "synthetic_aperture")
            bad("unknown section '" + k +
                "' (expected preprocess, window, estimators, synthetic_aperture)");
    }
    if (doc.has("preprocess"))
        for (const auto& kv : doc["preprocess"].asMap())
        {
            const std::string k = kv.first.as<std::string>();
            const auto& v = kv.second;
            if (k == "correct_subband_sign_80")
                c.pre.correctSubbandSign80 = v.as<bool>();
            else if (k == "correct_subband_sign_40")
                c.pre.correctSubbandSign40 = v.as<bool>();
            else if (k == "exclude_firmware_overwritten")
                c.pre.excludeFirmwareOverwritten = v.as<bool>();
            else if (k == "remove_sampling_time_offset")
                c.pre.removeSamplingTimeOffset = v.as<bool>();
            else if (k == "normalize_power")
                c.pre.normalizePower = v.as<bool>();
            else if (k == "min_rssi_dbm")
                c.pre.minRssi_dBm = v.as<double>();
            else if (k == "require_calibration")
                c.pre.requireCalibration = v.as<bool>();
            else if (k == "max_streams")
                c.pre.maxStreams = v.as<unsigned>();
            else
                bad("unknown preprocess option '" + k + "'");
        }
    if (doc.has("window"))
        for (const auto& kv : doc["window"].asMap())
        {
            const std::string k = kv.first.as<std::string>();
            if (k == "capacity")
                c.window.windowCapacity = kv.second.as<size_t>();
            else if (k == "max_age_s")
                c.window.windowMaxAge_s = kv.second.as<double>();
            else if (k == "stride")
                c.window.stride = std::max(1u, kv.second.as<unsigned>());
            else if (k == "max_span_without_odometry_s")
            {
                c.window.maxWindowSpanWithoutOdometry_s = kv.second.as<double>();
                if (!(c.window.maxWindowSpanWithoutOdometry_s >= 0))
                    bad("window.max_span_without_odometry_s must be >= 0");
            }
            else
                bad("unknown window option '" + k + "'");
        }
    if (doc.has("synthetic_aperture"))
        for (const auto& kv : doc["synthetic_aperture"].asMap())
        {
            const std::string k = kv.first.as<std::string>();
            if (k == "interval_s")
            {
                c.window.apertureInterval_s = kv.second.as<double>();
                if (!(c.window.apertureInterval_s >= 0))
                    bad("synthetic_aperture.interval_s must be >= 0");
            }
            else if (k == "peers")
            {
                if (!kv.second.isMap())
                    bad("synthetic_aperture.peers must map sensor labels to MAC addresses");
                for (const auto& peer : kv.second.asMap())
                {
                    const std::string label = peer.first.as<std::string>();
                    const std::string mac = peer.second.as<std::string>();
                    try
                    {
                        c.window.peerRecordings[label] = MacAddress::fromString(mac);
                    }
                    catch (const std::exception& e)
                    {
                        bad("synthetic_aperture.peers." + label + ": " + e.what());
                    }
                }
            }
            else
                bad("unknown synthetic_aperture option '" + k + "' (expected peers, interval_s)");
        }
    if (doc.has("estimators") && doc["estimators"].has(algo))
        c.estimatorParams = doc["estimators"][algo];
    return c;
}

}  // namespace mrpt_wifi::bearing
