/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/containers/yaml.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>

#include <string>

namespace mrpt_wifi::bearing
{
/** The options of a bearing chain (BearingProcessor) from one YAML file, shared by
 *  `csi-bearings --config` and the sensor's `bearing_options`, so both read it the same way:
 *  \code
 *  preprocess: {min_rssi_dbm: -80, require_calibration: false, max_streams: 4, ...}
 *  window: {capacity: 32, max_age_s: 1.0, stride: 1, max_span_without_odometry_s: 0.15}
 *  estimators: {music: {...}, aoa_only: {...}}   # per estimator name
 *  synthetic_aperture: {peers: {PEER_LABEL: "MAC", ...}, interval_s: 1.0}  # estimator sar
 *  \endcode */
struct BearingChainConfig
{
    PreprocessOptions pre;
    BearingProcessor::Options window;
    /** `estimators.<algo>` (a null node when the file has none for that estimator). */
    mrpt::containers::yaml estimatorParams;
};

/** Reads `path` (empty: all defaults). Unknown sections or options throw std::invalid_argument
 *  naming the file and the option. */
BearingChainConfig loadBearingChainConfig(const std::string& path, const std::string& algo);

}  // namespace mrpt_wifi::bearing
