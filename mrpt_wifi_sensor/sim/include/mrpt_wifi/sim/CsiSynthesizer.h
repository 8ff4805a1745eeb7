/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/sim/AntennaArray.h>
#include <mrpt_wifi/sim/ChannelModel.h>

#include <Eigen/Core>
#include <complex>
#include <vector>

namespace mrpt_wifi::sim
{
/** An antenna array placed in the world: which elements are used and where it points. */
struct ArrayPlacement
{
    const AntennaArray* array = nullptr;
    double yaw_rad = 0;         //!< world-frame yaw of the array frame
    unsigned elementsUsed = 0;  //!< first N elements (rx chains or tx streams)
};

/** Wideband multipath CSI, exact per subcarrier (DESIGN.md §5):
 *
 *   H[m][i][k] = Σ_p g_p · e^{-j2π f_k τ_p} · e^{+j2π f_k/c (a_i·u_arr,p)} · e^{+j2π f_k/c
 * (b_m·u_dep,p)}
 *
 * with f_k = f_c + k·312.5 kHz, a_i the receive element i and b_m the transmit element m (each in
 * its array frame), u_arr the unit vector from the receiver towards the arriving ray and u_dep
 * the unit vector of the departing ray, both rotated into the respective array frame. Each
 * subcarrier uses its own wavelength; nothing is narrowband.
 *
 * Cost: per (path, stream, chain) one complex exponential for the first subcarrier and one for
 * the subcarrier step, then a complex recurrence across subcarriers, vectorised over the
 * (stream, chain) pairs. No allocation once the workspace has grown. Not thread-safe (one
 * workspace per instance). */
class CsiSynthesizer
{
public:
    /** Writes the ideal CSI into `out` ([tx][rx][bin], bin = k + NFFT/2, NFFT bins per pair;
     *  resized), non-zero only for the occupied subcarriers |k| ≤ occupiedEdge(bandwidth). */
    void synthesize(
        const std::vector<PropagationPath>& paths, const ArrayPlacement& rx,
        const ArrayPlacement& tx, const Chanspec& chanspec, std::vector<std::complex<float>>& out);

    /** Highest occupied subcarrier index: 28 / 58 / 122 for 20 / 40 / 80 MHz. */
    static int occupiedEdge(unsigned bandwidthMHz);

private:
    std::vector<float> accRe_, accIm_;                  // [bin][pair], pairs padded
    std::vector<float> z0Re_, z0Im_, stepRe_, stepIm_;  // [chunk][path][lane]
    Eigen::ArrayXf angles_, cosines_, sines_;           // phasor angles of all paths
};

}  // namespace mrpt_wifi::sim
