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
    switch (bandwidthMHz)
    {
        case 20:
            return k20;
        case 40:
            return k40;
        case 80:
            return k80;
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

}  // namespace mrpt_wifi
