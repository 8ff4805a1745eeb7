/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/obs/CObservation.h>
#include <mrpt/serialization/CSerializable.h>

#include <cstdint>
#include <functional>
#include <string>

namespace mrpt_wifi
{
/** Reads every top-level object of a rawlog (gzip or plain; observation-only or
 * action/sensory-frame format), in file order. `onProgress(fraction of the file)` is called
 * now and then. When an object can't be read it throws std::runtime_error naming the file, the
 * object number and the compressed byte offset — after every object before it was delivered.
 * Returns the number of objects read. */
uint64_t forEachRawlogObject(
    const std::string& path,
    const std::function<void(mrpt::serialization::CSerializable::Ptr&)>& onObject,
    const std::function<void(double)>& onProgress = {});

/** As forEachRawlogObject(), delivering every observation: the top-level ones and those inside
 * sensory frames (actions are skipped). */
uint64_t forEachRawlogObservation(
    const std::string& path,
    const std::function<void(const mrpt::obs::CObservation::Ptr&)>& onObservation,
    const std::function<void(double)>& onProgress = {});

}  // namespace mrpt_wifi
