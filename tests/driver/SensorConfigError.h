/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>

#include <exception>
#include <string>

namespace mrpt_wifi::test
{
/** What CWiFiCSISensor::loadConfig says about section [CSI] of `ini` (empty if it accepts it). */
inline std::string sensorConfigError(const std::string& ini)
{
    mrpt::config::CConfigFileMemory cfg(ini);
    CWiFiCSISensor sensor;
    try
    {
        sensor.loadConfig(cfg, "CSI");
    }
    catch (const std::exception& e)
    {
        return e.what();
    }
    return {};
}
}  // namespace mrpt_wifi::test
