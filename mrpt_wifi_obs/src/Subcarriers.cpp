/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/Subcarriers.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
std::vector<int> symmetricRangeWithout(int edge, std::vector<int> excludedMagnitudes)
{
    std::vector<int> ks;
    for (int k = -edge; k <= edge; ++k)
        if (std::find(excludedMagnitudes.begin(), excludedMagnitudes.end(), std::abs(k)) ==
            excludedMagnitudes.end())
            ks.push_back(k);
    return ks;
}
}  // namespace

const std::vector<int>& dataSubcarriers(unsigned bandwidthMHz)
{
    static const std::vector<int> k20 = symmetricRangeWithout(28, {0, 7, 21});
    static const std::vector<int> k40 = symmetricRangeWithout(58, {0, 1, 11, 25, 53});
    static const std::vector<int> k80 = symmetricRangeWithout(122, {0, 1, 11, 39, 75, 103});
    // VHT 160: two 80 MHz segments at ∓128, each −122..−2, 2..122 → |k| in 6..126 and 130..250;
    // pilots ±25, ±53, ±89, ±117, ±139, ±167, ±203, ±231.
    static const std::vector<int> k160 = []
    {
        std::vector<int> ks;
        const std::vector<int> pilots = {25, 53, 89, 117, 139, 167, 203, 231};
        for (int k = -250; k <= 250; ++k)
        {
            const int a = std::abs(k);
            if (a < 6 || (a >= 127 && a <= 129)) continue;
            if (std::find(pilots.begin(), pilots.end(), a) != pilots.end()) continue;
            ks.push_back(k);
        }
        return ks;
    }();
    switch (bandwidthMHz)
    {
        case 20:
            return k20;
        case 40:
            return k40;
        case 80:
            return k80;
        case 160:
            return k160;
        default:
            throw std::invalid_argument(
                "no data subcarrier table for " + std::to_string(bandwidthMHz) + " MHz");
    }
}

std::vector<int> firmwareOverwrittenSubcarriers(unsigned bandwidthMHz)
{
    if (bandwidthMHz == 20) return {28, 29, 30};
    return {0, 1, 2};
}

bool inNegatedSubband(int k, unsigned bandwidthMHz)
{
    if (bandwidthMHz == 80) return k < -64;
    // 160: the lowest 20 MHz of each 80 MHz segment (segment-local k' = k ± 128 below −64).
    if (bandwidthMHz == 160) return k < -192 || (k >= 0 && k < 64);
    return false;
}

const std::vector<int>& htGroupedSubcarriers(unsigned bandwidthMHz)
{
    // 802.11n beamforming-feedback grouping: Ng = 2 at 20 MHz, Ng = 4 at 40 MHz (30 each), the
    // subcarriers the Intel 5300 CSI Tool reports.
    static const std::vector<int> g20 = []
    {
        std::vector<int> ks;
        for (int k = -28; k <= -2; k += 2) ks.push_back(k);
        ks.push_back(-1);
        for (int k = 1; k <= 27; k += 2) ks.push_back(k);
        ks.push_back(28);
        return ks;
    }();
    static const std::vector<int> g40 = []
    {
        std::vector<int> ks;
        for (int k = -58; k <= -2; k += 4) ks.push_back(k);
        for (int k = 2; k <= 58; k += 4) ks.push_back(k);
        return ks;
    }();
    if (bandwidthMHz == 20) return g20;
    if (bandwidthMHz == 40) return g40;
    throw std::invalid_argument(
        "no 802.11n subcarrier grouping for " + std::to_string(bandwidthMHz) + " MHz (20 or 40)");
}

}  // namespace mrpt_wifi
