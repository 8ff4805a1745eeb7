/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/AntennaArray.h>

namespace mrpt_wifi::sim
{
/** The simulator uses the project's one antenna-array model and file format
 *  (the YAML files in share/arrays/), the same the bearing estimators and the calibration read. */
using AntennaArray = mrpt_wifi::AntennaArray;
}  // namespace mrpt_wifi::sim
