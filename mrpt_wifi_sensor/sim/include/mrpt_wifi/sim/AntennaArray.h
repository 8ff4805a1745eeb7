/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>

#include <string>
#include <vector>

namespace mrpt_wifi::sim
{
/** Planar antenna array: element phase centres in the array's own frame (x forward, y left,
 *  metres), listed in port order (element i is receive core i, or transmit stream i).
 *
 * Geometry lives in files (share/arrays/NAME.yaml), one per device:
 * \code
 * name: rt-ac86u
 * elements:          # [x, y] metres, port order
 *   - [0.0, 0.0]
 *   - [0.0, 0.052]
 * \endcode
 */
struct AntennaArray
{
    std::string name;
    std::string description;
    std::vector<mrpt::math::TPoint2D> elements;
    std::string sourcePath;  //!< file it came from ("" if inline)

    size_t size() const { return elements.size(); }

    /** One isotropic element at the origin (a single-antenna device). */
    static AntennaArray singleElement();

    /** Loads an array file; throws std::runtime_error naming the file, line and key. */
    static AntennaArray fromYamlFile(const std::string& path);

    /** Far-field steering phase [rad] of element i for a plane wave whose source lies in
     *  direction `theta` [rad, array frame]: 2π/λ · (a_i · u(θ)), u = (cos θ, sin θ)
     *  (DESIGN.md §5). Positive: the element is closer to the source than the origin. */
    double steeringPhase(size_t i, double theta, double wavelength_m) const;
};

}  // namespace mrpt_wifi::sim
