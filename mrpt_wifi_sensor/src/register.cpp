/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/initializer.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <mrpt_wifi/sensor/CWiFiOdometryUdpSensor.h>

// The library's one initializer. rawlog-grabber finds drivers by bare class name
// ("driver = CWiFiCSISensor"); IMPLEMENTS_GENERIC_SENSOR does not register by itself.
MRPT_INITIALIZER(registerAllClasses_mrpt_wifi_sensor)
{
    mrpt_wifi::CWiFiCSISensor::doRegister();
    mrpt_wifi::CWiFiOdometryUdpSensor::doRegister();
}
