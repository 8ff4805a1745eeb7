/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/initializer.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>

// The library's one initializer: registers its classes with MRPT's class registry as soon as the
// .so is loaded (linked, or LD_PRELOAD into pf-localization). The map *type* (the name
// `wifiBearingMap` usable in .ini files) registers itself through MAP_DEFINITION_REGISTER.
MRPT_INITIALIZER(registerAllClasses_mrpt_wifi_localization)
{
    mrpt::rtti::registerClass(CLASS_ID(mrpt_wifi::CWiFiBearingMap));
}
