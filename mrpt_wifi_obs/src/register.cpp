/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/initializer.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/CObservationWiFiScan.h>

// The library's one initializer: makes its classes known to MRPT's class registry as soon as
// the .so is loaded (by linking or by rawlog-edit -p / rawlog-grabber -p).
MRPT_INITIALIZER(registerAllClasses_mrpt_wifi_obs)
{
    using namespace mrpt_wifi;
    mrpt::rtti::registerClass(CLASS_ID(CObservationWiFiCSI));
    mrpt::rtti::registerClass(CLASS_ID(CObservationWiFiScan));
    mrpt::rtti::registerClass(CLASS_ID(CObservationWiFiBearing));
}
