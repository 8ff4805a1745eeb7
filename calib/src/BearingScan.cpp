/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/calib/BearingScan.h>

#include <cmath>

namespace mrpt_wifi::calib
{
BearingScan::BearingScan(
    const AntennaArray& array, const SubcarrierLayout& layout, unsigned nRx, unsigned groups,
    double step_deg)
    : array_(array),
      nRx_(nRx),
      groups_(std::max(1u, std::min<unsigned>(groups, unsigned(layout.size()))))
{
    std::tie(lo_, hi_) = array.searchInterval();
    linear_ = array.isLinear() && array.size() >= 2;
    const double step = step_deg * M_PI / 180;
    const size_t nAngles = size_t(std::max(2.0, std::round((hi_ - lo_) / step)));
    for (size_t a = 0; a < nAngles; ++a)
        grid_.push_back(lo_ + (hi_ - lo_) * double(a) / double(nAngles));
    for (unsigned g = 0; g < groups_; ++g)
    {
        const auto range = CleanCsi::groupRange(layout.size(), groups_, g);
        double f = 0;
        for (size_t j = range.first; j < range.second; ++j) f += layout.frequencies_Hz[j];
        groupRange_.push_back(range);
        groupFreq_.push_back(f / double(range.second - range.first));
        gridSteer_.push_back(array.steeringMatrix(grid_, groupFreq_.back(), nRx));
    }
    R_.assign(groups_, Eigen::MatrixXcd::Zero(nRx, nRx));
}

double BearingScan::fold(double theta) const
{
    if (!linear_) return wrapAngle(theta);
    const double centre = 0.5 * (lo_ + hi_), half = 0.5 * (hi_ - lo_);
    const double rel = wrapAngle(theta - centre);
    if (rel >= -half && rel < half) return wrapAngle(theta);
    return array_.mirrorOf(theta);
}

double BearingScan::power(double theta) const
{
    double p = 0;
    for (unsigned g = 0; g < groups_; ++g)
    {
        const Eigen::VectorXcd a = array_.steeringVector(theta, groupFreq_[g], nRx_);
        p += (a.adjoint() * R_[g] * a)(0, 0).real();
    }
    return p;
}

double BearingScan::estimate(
    const Eigen::MatrixXcf& H, unsigned nTx, const Eigen::MatrixXcf* factors)
{
    work_ = H;
    if (factors)
        for (unsigned m = 0; m < nTx; ++m)
            work_.middleRows(Eigen::Index(m * nRx_), nRx_).array() *= factors->array();
    for (unsigned g = 0; g < groups_; ++g)
    {
        const auto [b, e] = groupRange_[g];
        Eigen::MatrixXcf acc = Eigen::MatrixXcf::Zero(nRx_, nRx_);
        for (unsigned m = 0; m < nTx; ++m)
        {
            const auto blk =
                work_.block(Eigen::Index(m * nRx_), Eigen::Index(b), nRx_, Eigen::Index(e - b));
            acc.noalias() += blk * blk.adjoint();
        }
        R_[g] = acc.cast<std::complex<double>>();
    }
    // Grid scan: P(θ_a) = Σ_g Re(a^H R_g a), all angles at once.
    Eigen::VectorXd P = Eigen::VectorXd::Zero(Eigen::Index(grid_.size()));
    for (unsigned g = 0; g < groups_; ++g)
        P += (gridSteer_[g].conjugate().cwiseProduct(R_[g] * gridSteer_[g]))
                 .colwise()
                 .sum()
                 .real()
                 .transpose();
    Eigen::Index best = 0;
    P.maxCoeff(&best);

    // Parabolic refinement through the peak and its neighbours.
    const Eigen::Index N = P.size();
    const bool wraps = !linear_;
    if (!wraps && (best == 0 || best == N - 1)) return grid_[size_t(best)];
    const double pm = P[(best + N - 1) % N], p0 = P[best], pp = P[(best + 1) % N];
    const double den = pm - 2 * p0 + pp;
    const double step = (hi_ - lo_) / double(N);
    double off = den < 0 ? 0.5 * (pm - pp) / den : 0.0;
    off = std::clamp(off, -0.5, 0.5);
    return wrapAngle(grid_[size_t(best)] + off * step);
}

}  // namespace mrpt_wifi::calib
