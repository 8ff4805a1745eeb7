/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/calib/PhaseCalibrator.h>

#include <string>
#include <vector>

namespace mrpt_wifi::calib
{
/** Bearing errors [deg] of frames (drive mode) against their expected bearings, with the
 *  calibration applied (nullptr: uncalibrated). Frames without geometry are skipped. */
std::vector<double> bearingErrors_deg(
    const std::vector<CalibrationFrame>& frames, const AntennaArray& array,
    const PhaseCalibration* calib);

/** Median (0.5) or other quantile of a list; NaN for an empty one. */
double quantile(std::vector<double> v, double q);

struct CheckOptions
{
    /** Stale if the median bearing error with the calibration exceeds this [deg]... */
    double staleMedianError_deg = 8.0;
    /** ... or the RMS phase residual exceeds max(factor × the file's residual, floor) [rad]. */
    double staleResidualFactor = 3.0;
    double staleResidualFloor_rad = 0.6;
    size_t minFrames = 30;
};

/** Does a calibration still fit the receiver? */
struct CheckResult
{
    size_t frames = 0;
    double medianError_deg = 0, p90Error_deg = 0;
    double medianErrorUncalibrated_deg = 0;
    double phaseResidual_rad = 0;  //!< sqrt(−ln coherence) of the calibrated, suppressed CSI
    double residualLimit_rad = 0;
    bool enoughFrames = false;
    bool stale = false;
    std::string message;  //!< one line for the user (what to do)
};

/** The residuals of a calibration on frames with known geometry (e.g. a new short drive, or
 *  the calibration drive after a reboot): bearing errors and phase residual, and the verdict.
 *  After a reboot the per-chain offsets change and both jump. */
CheckResult calibrationResidual(
    const std::vector<CalibrationFrame>& frames, const AntennaArray& array,
    const PhaseCalibration& calib, const CheckOptions& opts = {});

}  // namespace mrpt_wifi::calib
