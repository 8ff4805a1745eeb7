/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sim/AntennaArray.h>

#include <cmath>

#include "YamlReader.h"

namespace mrpt_wifi::sim
{
AntennaArray AntennaArray::singleElement()
{
    AntennaArray a;
    a.name = "single";
    a.elements.emplace_back(0.0, 0.0);
    return a;
}

double AntennaArray::steeringPhase(size_t i, double theta, double wavelength_m) const
{
    const auto& e = elements.at(i);
    return 2.0 * M_PI / wavelength_m * (e.x * std::cos(theta) + e.y * std::sin(theta));
}

namespace detail
{
/** Reads an array map {name, description, elements}; shared by files and inline arrays. */
AntennaArray readAntennaArray(const YamlNode& n)
{
    n.allowOnly({"name", "description", "elements"});
    AntennaArray a;
    a.name = n.stringOr("name", "unnamed");
    a.description = n.stringOr("description", "");
    const YamlNode elems = n["elements"];
    if (!elems.isSequence() || elems.size() == 0)
        elems.fail("expected a non-empty list of [x, y] element positions in metres");
    for (size_t i = 0; i < elems.size(); ++i) a.elements.push_back(elems.at(i).asPoint2D());
    for (size_t i = 0; i < a.elements.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (a.elements[i] == a.elements[j])
                elems.at(i).fail(
                    "element " + std::to_string(i) + " coincides with element " +
                    std::to_string(j));
    return a;
}
}  // namespace detail

AntennaArray AntennaArray::fromYamlFile(const std::string& path)
{
    auto doc = detail::YamlDocument::load(path);
    AntennaArray a = detail::readAntennaArray(detail::YamlNode::root(doc));
    a.sourcePath = path;
    return a;
}

}  // namespace mrpt_wifi::sim
