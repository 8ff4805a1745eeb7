/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/calib/BearingScan.h>
#include <mrpt_wifi/calib/CalibrationCheck.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

namespace mrpt_wifi::calib
{
double quantile(std::vector<double> v, double q)
{
    if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
    const size_t k = std::min(v.size() - 1, size_t(std::floor(q * double(v.size() - 1) + 0.5)));
    std::nth_element(v.begin(), v.begin() + long(k), v.end());
    return v[k];
}

namespace
{
/** Scanners and calibration factors per channel layout, built on first use. */
struct PerLayout
{
    std::unique_ptr<BearingScan> scan;
    Eigen::MatrixXcf factors;
};

PerLayout& perLayout(
    std::map<const SubcarrierLayout*, PerLayout>& cache, const CalibrationFrame& f,
    const AntennaArray& array, const PhaseCalibration* calib)
{
    auto& p = cache[f.layout.get()];
    if (!p.scan)
    {
        p.scan = std::make_unique<BearingScan>(array, *f.layout, f.nRx);
        if (calib)
        {
            if (!calib->matchesChannel(f.chanspec))
                throw CalibrationError(
                    "the calibration is for " + calib->chanspec.asString() +
                    ", the frames are on " + f.chanspec.asString());
            p.factors = calibrationFactors(*calib, *f.layout, f.nRx);
        }
    }
    return p;
}
}  // namespace

std::vector<double> bearingErrors_deg(
    const std::vector<CalibrationFrame>& frames, const AntennaArray& array,
    const PhaseCalibration* calib)
{
    std::map<const SubcarrierLayout*, PerLayout> cache;
    std::vector<double> err;
    err.reserve(frames.size());
    for (const auto& f : frames)
    {
        if (!f.hasGeometry) continue;
        auto& p = perLayout(cache, f, array, calib);
        const double est = p.scan->estimate(f.H, f.nTx, calib ? &p.factors : nullptr);
        err.push_back(angleDistance(est, p.scan->fold(f.expectedAoa_rad)) * 180 / M_PI);
    }
    return err;
}

CheckResult calibrationResidual(
    const std::vector<CalibrationFrame>& frames, const AntennaArray& array,
    const PhaseCalibration& calib, const CheckOptions& opts)
{
    CheckResult r;
    const auto after = bearingErrors_deg(frames, array, &calib);
    const auto before = bearingErrors_deg(frames, array, nullptr);
    r.frames = after.size();
    r.enoughFrames = r.frames >= opts.minFrames;
    r.medianError_deg = quantile(after, 0.5);
    r.p90Error_deg = quantile(after, 0.9);
    r.medianErrorUncalibrated_deg = quantile(before, 0.5);

    // Phase residual: how far the calibrated, bearing-suppressed CSI is from equal phases.
    std::map<const SubcarrierLayout*, Eigen::MatrixXcf> factors;
    double num = 0, den = 0;
    for (const auto& f : frames)
    {
        if (!f.hasGeometry) continue;
        auto& F = factors[f.layout.get()];
        if (F.size() == 0) F = calibrationFactors(calib, *f.layout, f.nRx);
        const size_t nSub = f.layout->size();
        for (size_t j = 0; j < nSub; ++j)
        {
            const Eigen::VectorXcd a =
                array.steeringVector(f.expectedAoa_rad, f.layout->frequencies_Hz[j], f.nRx);
            for (unsigned m = 0; m < f.nTx; ++m)
            {
                std::complex<double> sum = 0;
                double pow = 0;
                for (unsigned i = 0; i < f.nRx; ++i)
                {
                    const std::complex<double> y =
                        std::complex<double>(
                            f.H(Eigen::Index(m * f.nRx + i), Eigen::Index(j)) *
                            F(i, Eigen::Index(j))) *
                        std::conj(a[i]);
                    sum += y;
                    pow += std::norm(y);
                }
                num += std::norm(sum);
                den += f.nRx * pow;
            }
        }
    }
    const double coh = den > 0 ? std::clamp(num / den, 1e-12, 1.0) : 1e-12;
    r.phaseResidual_rad = std::sqrt(-std::log(coh));
    r.residualLimit_rad =
        std::max(opts.staleResidualFactor * calib.residual_rad, opts.staleResidualFloor_rad);

    std::ostringstream msg;
    msg.setf(std::ios::fixed);
    msg.precision(1);
    if (!r.enoughFrames)
    {
        msg << "only " << r.frames << " frames with known geometry (need " << opts.minFrames
            << "): cannot judge the calibration";
    }
    else
    {
        const bool badBearing = r.medianError_deg > opts.staleMedianError_deg;
        const bool badPhase = r.phaseResidual_rad > r.residualLimit_rad;
        r.stale = badBearing || badPhase;
        if (r.stale)
            msg << "STALE: the calibration no longer fits this receiver: median bearing error "
                << r.medianError_deg << "° (limit " << opts.staleMedianError_deg
                << "°), phase residual " << r.phaseResidual_rad << " rad (limit "
                << r.residualLimit_rad
                << " rad). The router was probably rebooted or the hardware changed: "
                   "recalibrate with wifi-calibrate.";
        else
            msg << "OK: median bearing error " << r.medianError_deg << "° (uncalibrated "
                << r.medianErrorUncalibrated_deg << "°), phase residual " << r.phaseResidual_rad
                << " rad (limit " << r.residualLimit_rad << " rad)";
    }
    r.message = msg.str();
    return r;
}

}  // namespace mrpt_wifi::calib
