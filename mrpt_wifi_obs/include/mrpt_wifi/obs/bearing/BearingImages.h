/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/img/CImage.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/bearing/BearingEstimator.h>

#include <complex>
#include <string>
#include <vector>

namespace mrpt_wifi::bearing
{
/** Magnitude [dB] and unwrapped phase [rad] per antenna over subcarriers, two stacked panels
 *  (OpenCV, colour per antenna, labelled axes). `csi` is [antenna][subcarrier]. */
mrpt::img::CImage renderMagnitudePhase(
    const std::vector<int>& subcarriers, const std::vector<std::vector<std::complex<float>>>& csi,
    const std::string& title);
/** The CSI of one stream of a preprocessed frame (what the estimators see). */
mrpt::img::CImage renderMagnitudePhase(const CleanCsi& frame, unsigned stream = 0);
/** The data subcarriers of one stream of a raw frame (no correction: shows the firmware's
 *  sub-band sign step and the per-packet slope). */
mrpt::img::CImage renderMagnitudePhase(const CObservationWiFiCSI& frame, unsigned stream = 0);

/** The bearing × delay profile as a colour-mapped heat map in dB (or, for a 1-D profile, a
 *  curve), with the chosen peak marked and the result in the title. */
mrpt::img::CImage renderBearingProfile(
    const BearingProfile& profile, const BearingResult& result, const std::string& title);

/** Wraps an image as a CObservationImage for a rawlog (RawLogViewer shows it). */
mrpt::obs::CObservationImage::Ptr asImageObservation(
    const mrpt::img::CImage& image, mrpt::Clock::time_point timestamp,
    const std::string& sensorLabel);

}  // namespace mrpt_wifi::bearing
