/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace mrpt_wifi::localization
{
/** What a bearing consumer needs to know about an antenna array: is it linear (then every angle
 *  has a mirror image across the array axis) and along which direction does it lie. */
struct ArrayGeometry
{
    std::vector<mrpt::math::TPoint2D> elements;  //!< [m], array frame (x boresight, y left)
    bool linear = true;                          //!< single elements count as linear
    double axis_rad = 0;  //!< direction of the array line (first to farthest element)

    /** Computes `linear` and `axis_rad` from the elements (tolerance 1 mm off the line). */
    static ArrayGeometry fromElements(std::vector<mrpt::math::TPoint2D> elements);
    /** Mirror of θ across the axis for linear arrays (wrapped to (−π, π]); θ for 2-D arrays. */
    double mirrorOf(double theta) const;
    /** True if θ lies in the half-plane [broadside − 90°, broadside + 90°] that estimators report
     *  first (broadside = axis − 90° folded to the front, |·| ≤ 90°). Always true for 2-D. */
    bool inFrontHalf(double theta) const;
};

/** One transmitter of known pose (an access point or a mapped device). */
struct KnownTransmitter
{
    std::string name;
    MacAddress mac;
    mrpt::math::TPose2D pose;  //!< array origin and boresight yaw in the world frame [m, rad]
    ArrayGeometry array;       //!< one element at the origin if not given
};

/** A set of transmitters loaded from YAML, indexed by MAC and by name.
 *
 * File format (also what `wifi-sim --truth-dir` writes as transmitters.yaml, so a simulated
 * truth can be used as a map directly). Angles in degrees, metres, world frame:
 * \code
 * transmitters:
 *   - name: ap-nw                 # optional (default: the MAC), unique
 *     mac: '02:00:00:00:01:01'    # required, unique
 *     position: [0.3, 4.7]        # required
 *     yaw_deg: -45                # boresight of the array frame (default 0)
 *     array: ../arrays/ap-linear-4.yaml          # array file (relative to this file, else
 *                                                # by name: ap-linear-4), or
 *     array_elements: [[0, -0.039], [0, 0.039]]  # inline elements (x, y) [m]
 * \endcode
 * Keys written by the simulator that don't matter here (channel, streams, frame_rate_hz,
 * tx_power_dbm) are accepted; any other key is an error. Duplicate MACs or names are errors.
 */
class TransmitterMap
{
public:
    /** Throws std::runtime_error naming the file, the entry and the problem. */
    static TransmitterMap fromYamlFile(const std::string& path);
    static TransmitterMap fromYamlText(
        const std::string& text, const std::string& displayName = "<text>",
        const std::string& baseDir = ".");
    /** Writes the file format above (inline elements). */
    std::string asYamlText() const;

    /** Adds one; throws std::invalid_argument on a duplicate MAC or name. */
    void add(const KnownTransmitter& t);

    size_t size() const { return list_.size(); }
    bool empty() const { return list_.empty(); }
    const std::vector<KnownTransmitter>& transmitters() const { return list_; }
    const KnownTransmitter& at(size_t i) const { return list_.at(i); }

    /** Index of a transmitter by MAC, or -1. */
    int indexOf(const MacAddress& mac) const;
    const KnownTransmitter* find(const MacAddress& mac) const;
    /** By name or MAC text ("ap-nw" or "02:00:00:00:01:01"); nullptr if unknown. */
    const KnownTransmitter* findByText(const std::string& nameOrMac) const;

    /** Axis-aligned bounds of the transmitter positions grown by `margin_m`. */
    void bounds(double margin_m, double& xmin, double& xmax, double& ymin, double& ymax) const;

private:
    std::vector<KnownTransmitter> list_;
    std::unordered_map<MacAddress, int> byMac_;
    std::unordered_map<std::string, int> byName_;
};

/** Reads the element list of an array file (share/arrays/NAME.yaml: `elements: [[x, y], ...]`). */
ArrayGeometry loadArrayFile(const std::string& path);

/** Wraps an angle to (−π, π]. */
double wrapToPi(double a);

}  // namespace mrpt_wifi::localization
