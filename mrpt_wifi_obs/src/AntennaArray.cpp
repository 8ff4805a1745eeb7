/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/containers/yaml.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/ConfigPaths.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
[[noreturn]] void fail(const std::string& where, const std::string& what)
{
    throw std::runtime_error("antenna array " + where + ": " + what);
}

AntennaArray parseArray(const mrpt::containers::yaml& doc, const std::string& where)
{
    if (!doc.isMap()) fail(where, "expected a map with keys name, description, elements, cores");
    for (const auto& kv : doc.asMap())
    {
        const std::string key = kv.first.as<std::string>();
        if (key != "name" && key != "description" && key != "elements" && key != "cores")
            fail(where, "unknown key '" + key + "' (expected name, description, elements, cores)");
    }
    AntennaArray a;
    if (!doc.has("name")) fail(where, "missing key 'name' (the device the geometry belongs to)");
    a.name = doc["name"].as<std::string>();
    if (doc.has("description")) a.description = doc["description"].as<std::string>();
    if (!doc.has("elements") || !doc["elements"].isSequence() ||
        doc["elements"].asSequence().empty())
        fail(where, "'elements' must be a non-empty list of [x, y] positions in metres");
    const auto& seq = doc["elements"].asSequence();
    for (size_t i = 0; i < seq.size(); ++i)
    {
        const auto& e = seq[i];
        if (!e.isSequence() || e.asSequence().size() != 2)
            fail(where, "elements[" + std::to_string(i) + "] must be [x, y] (metres)");
        double xy[2];
        for (int c = 0; c < 2; ++c)
        {
            try
            {
                xy[c] = e.asSequence()[size_t(c)].as<double>();
            }
            catch (const std::exception&)
            {
                fail(where, "elements[" + std::to_string(i) + "] holds a non-number");
            }
            if (!std::isfinite(xy[c]) || std::abs(xy[c]) > 10.0)
                fail(where, "elements[" + std::to_string(i) + "] is not a position within 10 m");
        }
        a.elements.emplace_back(xy[0], xy[1]);
    }
    for (size_t i = 0; i < a.elements.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if ((a.elements[i] - a.elements[j]).norm() < 1e-6)
                fail(
                    where, "element " + std::to_string(i) + " coincides with element " +
                               std::to_string(j));
    if (a.elements.size() > 8)
        fail(where, "more than 8 elements (Nexmon reports at most 8 chains)");
    if (doc.has("cores"))
    {
        const auto& c = doc["cores"];
        if (!c.isSequence() || c.asSequence().size() != a.elements.size())
            fail(
                where, "'cores' must list one receive core per element (" +
                           std::to_string(a.elements.size()) + " numbers, e.g. [0, 1, 3])");
        for (size_t i = 0; i < a.elements.size(); ++i)
        {
            int core = -1;
            try
            {
                core = c.asSequence()[i].as<int>();
            }
            catch (const std::exception&)
            {
            }
            if (core < 0 || core > 7)
                fail(where, "cores[" + std::to_string(i) + "] is not a core number 0..7");
            for (size_t j = 0; j < i; ++j)
                if (a.cores[j] == unsigned(core))
                    fail(
                        where,
                        "cores[" + std::to_string(i) + "] repeats core " + std::to_string(core));
            a.cores.push_back(unsigned(core));
        }
    }
    return a;
}
}  // namespace

double wrapAngle(double a)
{
    a = std::remainder(a, 2 * M_PI);
    return a <= -M_PI ? a + 2 * M_PI : a;
}

double angleDistance(double a, double b)
{
    return std::abs(wrapAngle(a - b));
}

AntennaArray AntennaArray::singleElement()
{
    AntennaArray a;
    a.name = "single";
    a.description = "one isotropic element at the origin";
    a.elements.emplace_back(0.0, 0.0);
    return a;
}

AntennaArray AntennaArray::fromYamlFile(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error("antenna array '" + path + "': cannot open the file");
    std::stringstream ss;
    ss << f.rdbuf();
    AntennaArray a = fromYamlText(ss.str(), "'" + path + "'");
    a.sourcePath = path;
    return a;
}

AntennaArray AntennaArray::fromFileOrName(
    const std::string& value, const std::string& what, const std::string& baseDir)
{
    config::ResolvedPath found;
    try
    {
        found = config::resolveConfigPath(value, baseDir, "arrays", what);
    }
    catch (const std::invalid_argument& e)
    {
        throw std::runtime_error(e.what());
    }
    if (found.path.empty()) throw std::runtime_error(what + ": no antenna array given");
    return fromYamlFile(found.path);
}

AntennaArray AntennaArray::fromYamlText(const std::string& text, const std::string& displayName)
{
    mrpt::containers::yaml doc;
    try
    {
        doc = mrpt::containers::yaml::FromText(text);
    }
    catch (const std::exception& e)
    {
        fail(displayName, std::string("not valid YAML: ") + e.what());
    }
    return parseArray(doc, displayName);
}

std::string AntennaArray::asYamlText() const
{
    std::ostringstream o;
    o.precision(9);
    o << "name: " << name << "\n";
    if (!description.empty()) o << "description: " << description << "\n";
    o << "elements:\n";
    for (const auto& e : elements) o << "  - [" << e.x << ", " << e.y << "]\n";
    if (!cores.empty())
    {
        o << "cores: [";
        for (size_t i = 0; i < cores.size(); ++i) o << (i ? ", " : "") << cores[i];
        o << "]\n";
    }
    return o.str();
}

AntennaArray AntennaArray::firstElements(size_t n) const
{
    if (n > elements.size())
        throw std::invalid_argument(
            "antenna array '" + name + "' has " + std::to_string(elements.size()) + " elements, " +
            std::to_string(n) + " requested");
    AntennaArray a = *this;
    a.elements.resize(n);
    if (!a.cores.empty()) a.cores.resize(n);
    return a;
}

bool AntennaArray::isLinear(double tolerance_m) const
{
    if (elements.size() <= 2) return true;
    const double axis = axisDirection();
    const mrpt::math::TPoint2D dir(std::cos(axis), std::sin(axis));
    for (const auto& e : elements)
    {
        const auto d = e - elements[0];
        if (std::abs(d.x * dir.y - d.y * dir.x) > tolerance_m) return false;
    }
    return true;
}

double AntennaArray::axisDirection() const
{
    // The longest baseline from element 0 is the most accurate estimate of the line.
    double best = 0, dir = 0;
    for (const auto& e : elements)
    {
        const auto d = e - elements[0];
        if (d.norm() > best)
        {
            best = d.norm();
            dir = std::atan2(d.y, d.x);
        }
    }
    return dir;
}

double AntennaArray::broadside() const
{
    if (!isLinear() || elements.size() < 2) return 0.0;
    const double b = wrapAngle(axisDirection() - M_PI / 2);
    return std::abs(b) <= M_PI / 2 + 1e-12 ? b : wrapAngle(b + M_PI);
}

double AntennaArray::mirrorOf(double theta) const
{
    if (elements.size() < 2 || !isLinear()) return wrapAngle(theta);
    return wrapAngle(2 * axisDirection() - theta);
}

std::pair<double, double> AntennaArray::searchInterval() const
{
    if (elements.size() >= 2 && isLinear())
    {
        const double b = broadside();
        return {b - M_PI / 2, b + M_PI / 2};
    }
    return {-M_PI, M_PI};
}

double AntennaArray::projection(size_t i, double theta) const
{
    const auto& e = elements.at(i);
    return e.x * std::cos(theta) + e.y * std::sin(theta);
}

double AntennaArray::steeringPhase(size_t i, double theta, double frequency_Hz) const
{
    return 2 * M_PI * frequency_Hz / kSpeedOfLightMps * projection(i, theta);
}

Eigen::VectorXcd AntennaArray::steeringVector(double theta, double frequency_Hz, size_t n) const
{
    if (n == 0) n = size();
    Eigen::VectorXcd a(n);
    for (size_t i = 0; i < n; ++i)
        a[Eigen::Index(i)] = std::polar(1.0, steeringPhase(i, theta, frequency_Hz));
    return a;
}

Eigen::MatrixXcd AntennaArray::steeringMatrix(
    const std::vector<double>& thetas, double frequency_Hz, size_t n) const
{
    if (n == 0) n = size();
    Eigen::MatrixXcd A(n, thetas.size());
    for (size_t j = 0; j < thetas.size(); ++j)
        A.col(Eigen::Index(j)) = steeringVector(thetas[j], frequency_Hz, n);
    return A;
}

Eigen::MatrixXcd AntennaArray::wideband(
    double theta, const std::vector<double>& frequencies_Hz, size_t n) const
{
    if (n == 0) n = size();
    Eigen::MatrixXcd A(n, frequencies_Hz.size());
    for (size_t k = 0; k < frequencies_Hz.size(); ++k)
        A.col(Eigen::Index(k)) = steeringVector(theta, frequencies_Hz[k], n);
    return A;
}

double AntennaArray::aoaCramerRaoBound(
    double theta, const std::vector<double>& frequencies_Hz, double snr,
    double snapshotsPerFrequency, size_t n) const
{
    if (n == 0) n = size();
    double information = 0;
    for (double f : frequencies_Hz)
    {
        // ∂/∂θ of 2π f/c (x cos θ + y sin θ); the mean over elements is a common phase, which
        // the unknown complex gain absorbs.
        std::vector<double> psi(n);
        double mean = 0;
        for (size_t i = 0; i < n; ++i)
        {
            const auto& e = elements[i];
            psi[i] =
                2 * M_PI * f / kSpeedOfLightMps * (-e.x * std::sin(theta) + e.y * std::cos(theta));
            mean += psi[i] / double(n);
        }
        for (double p : psi) information += (p - mean) * (p - mean);
    }
    information *= 2 * snr * snapshotsPerFrequency;
    return information > 0 ? 1.0 / std::sqrt(information) : INFINITY;
}

}  // namespace mrpt_wifi
