/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>

#include <Eigen/Core>
#include <vector>

namespace mrpt_wifi::calib
{
/** A plain wideband Bartlett bearing scan used to measure what a calibration does to bearings
 *  (before/after, staleness). Deliberately simple and independent of the bearing estimators so
 *  the check does not depend on their tuning: P(θ) = Σ_g a_g(θ)^H R_g a_g(θ) over `groups`
 *  sub-bands (each with its own centre frequency), a 1° grid over the array's unambiguous
 *  interval, then a parabolic refinement of the peak. */
class BearingScan
{
public:
    BearingScan(
        const AntennaArray& array, const SubcarrierLayout& layout, unsigned nRx,
        unsigned groups = 8, double step_deg = 1.0);

    /** Bearing [rad] of H ([(stream·nRx + rx)][subcarrier], nTx streams), multiplied first by
     *  `factors` ([rx][subcarrier]) when given. */
    double estimate(const Eigen::MatrixXcf& H, unsigned nTx, const Eigen::MatrixXcf* factors);

    /** The expected bearing as the scan can report it: linear arrays fold it into their
     *  half-plane (mirror image), 2-D arrays leave it alone. */
    double fold(double theta) const;

private:
    double power(double theta) const;
    const AntennaArray& array_;
    unsigned nRx_, groups_;
    std::vector<double> groupFreq_;
    std::vector<std::pair<size_t, size_t>> groupRange_;
    std::vector<double> grid_;
    std::vector<Eigen::MatrixXcd> gridSteer_;  //!< [group] nRx × angles
    std::vector<Eigen::MatrixXcd> R_;          //!< [group] of the current frame
    Eigen::MatrixXcf work_;
    double lo_, hi_;
    bool linear_;
};

}  // namespace mrpt_wifi::calib
