/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/bearing/BearingEstimator.h>

#include <algorithm>
#include <stdexcept>

namespace mrpt_wifi::bearing
{
namespace
{
template <class T>
T read(const mrpt::containers::yaml& node, const std::string& key, const std::string& who)
{
    try
    {
        return node.as<T>();
    }
    catch (const std::exception&)
    {
        throw std::invalid_argument(who + ": option '" + key + "' has a value of the wrong type");
    }
}

void requireRange(double v, double lo, double hi, const std::string& key, const std::string& who)
{
    if (!(v >= lo && v <= hi))
        throw std::invalid_argument(
            who + ": option '" + key + "' = " + std::to_string(v) + " is outside [" +
            std::to_string(lo) + ", " + std::to_string(hi) + "]");
}
}  // namespace

void EstimatorOptions::load(
    const mrpt::containers::yaml& params, const std::vector<std::string>& allowed,
    const std::string& estimatorName)
{
    if (params.isNullNode() || params.empty()) return;
    const std::string who = "estimator '" + estimatorName + "'";
    if (!params.isMap()) throw std::invalid_argument(who + ": options must be a map key: value");
    for (const auto& kv : params.asMap())
    {
        const std::string key = kv.first.as<std::string>();
        const auto& v = kv.second;
        if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
        {
            std::string list;
            for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
            throw std::invalid_argument(
                who + ": unknown option '" + key + "' (known: " + list + ")");
        }
        if (key == "angle_bins")
        {
            angleBins = read<unsigned>(v, key, who);
            requireRange(angleBins, 8, 3600, key, who);
        }
        else if (key == "delay_bins")
        {
            delayBins = read<unsigned>(v, key, who);
            requireRange(delayBins, 3, 4096, key, who);
        }
        else if (key == "delay_min_ns")
            delayMin_ns = read<double>(v, key, who);
        else if (key == "delay_max_ns")
            delayMax_ns = read<double>(v, key, who);
        else if (key == "delay_decimation")
        {
            delayDecimation = read<unsigned>(v, key, who);
            requireRange(delayDecimation, 1, 8, key, who);
        }
        else if (key == "window")
        {
            window = read<unsigned>(v, key, who);
            requireRange(window, 1, 1000, key, who);
        }
        else if (key == "frequency_groups")
        {
            frequencyGroups = read<unsigned>(v, key, who);
            requireRange(frequencyGroups, 1, 64, key, who);
        }
        else if (key == "refine")
            refine = read<bool>(v, key, who);
        else if (key == "std_floor_deg")
        {
            stdFloor_deg = read<double>(v, key, who);
            requireRange(stdFloor_deg, 0, 90, key, who);
        }
        else if (key == "keep_profile")
            keepProfile = read<bool>(v, key, who);
        else if (key == "max_paths")
        {
            maxPaths = read<unsigned>(v, key, who);
            requireRange(maxPaths, 1, 32, key, who);
        }
        else if (key == "subspace_threshold")
        {
            subspaceThreshold = read<double>(v, key, who);
            requireRange(subspaceThreshold, 1, 1e9, key, who);
        }
        else if (key == "components")
        {
            components = read<unsigned>(v, key, who);
            requireRange(components, 1, 16, key, who);
        }
        else if (key == "subcarrier_step")
        {
            subcarrierStep = read<unsigned>(v, key, who);
            requireRange(subcarrierStep, 1, 16, key, who);
        }
        else if (key == "smoothing_length")
        {
            smoothingLength = read<unsigned>(v, key, who);
            requireRange(smoothingLength, 2, 128, key, who);
        }
        else if (key == "direct_path_power_ratio")
        {
            directPathPowerRatio = read<double>(v, key, who);
            requireRange(directPathPowerRatio, 0, 1, key, who);
        }
        else if (key == "aperture_s")
        {
            aperture_s = read<double>(v, key, who);
            requireRange(aperture_s, 0.1, 600, key, who);
        }
        else if (key == "min_aperture_m")
        {
            minAperture_m = read<double>(v, key, who);
            requireRange(minAperture_m, 0.01, 100, key, who);
        }
        else if (key == "position_std_m")
        {
            positionStd_m = read<double>(v, key, who);
            requireRange(positionStd_m, 0, 10, key, who);
        }
        else if (key == "mover_chain")
        {
            moverChain = read<unsigned>(v, key, who);
            requireRange(moverChain, 0, 7, key, who);
        }
        else if (key == "peer_chain")
        {
            peerChain = read<unsigned>(v, key, who);
            requireRange(peerChain, 0, 7, key, who);
        }
        else if (key == "aod_method")
        {
            aodMethod = read<std::string>(v, key, who);
            if (aodMethod != "bartlett" && aodMethod != "music")
                throw std::invalid_argument(who + ": aod_method must be bartlett or music");
        }
    }
    if (!(delayMax_ns > delayMin_ns))
        throw std::invalid_argument(who + ": delay_max_ns must exceed delay_min_ns");
}

void BearingEstimator::configure(const mrpt::containers::yaml& params)
{
    opts_.load(params, parameterKeys(), name());
}

}  // namespace mrpt_wifi::bearing
