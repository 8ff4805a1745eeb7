/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/containers/yaml.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/obs/ConfigPaths.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::localization
{
using mrpt::math::TPoint2D;
using node_t = mrpt::containers::yaml::node_t;

double wrapToPi(double a)
{
    a = std::fmod(a + M_PI, 2 * M_PI);
    if (a <= 0) a += 2 * M_PI;
    return a - M_PI;
}

ArrayGeometry ArrayGeometry::fromElements(std::vector<TPoint2D> elements)
{
    ArrayGeometry g;
    g.elements = std::move(elements);
    if (g.elements.empty()) g.elements.emplace_back(0, 0);
    // The axis runs from the first element to the one farthest from it.
    const auto& a = g.elements.front();
    double best = 0;
    TPoint2D far = a;
    for (const auto& e : g.elements)
    {
        const double d = std::hypot(e.x - a.x, e.y - a.y);
        if (d > best) best = d, far = e;
    }
    if (best < 1e-9)
    {
        g.linear = true;  // a single element: no direction at all, but nothing 2-D either
        g.axis_rad = 0;
        return g;
    }
    g.axis_rad = std::atan2(far.y - a.y, far.x - a.x);
    const double ux = std::cos(g.axis_rad), uy = std::sin(g.axis_rad);
    g.linear = true;
    for (const auto& e : g.elements)
        if (std::abs(-(e.x - a.x) * uy + (e.y - a.y) * ux) > 1e-3) g.linear = false;
    return g;
}

double ArrayGeometry::mirrorOf(double theta) const
{
    if (!linear || elements.size() < 2) return wrapToPi(theta);
    return wrapToPi(2 * axis_rad - theta);
}

bool ArrayGeometry::inFrontHalf(double theta) const
{
    if (!linear || elements.size() < 2) return true;
    double broadside = wrapToPi(axis_rad - M_PI / 2);
    if (std::abs(broadside) > M_PI / 2) broadside = wrapToPi(broadside + M_PI);
    return std::abs(wrapToPi(theta - broadside)) <= M_PI / 2 + 1e-12;
}

namespace
{
[[noreturn]] void fail(const std::string& file, const node_t& n, const std::string& msg)
{
    throw std::runtime_error(file + ":" + std::to_string(n.marks.line + 1) + ": " + msg);
}

double number(const std::string& file, const node_t& n, const std::string& what)
{
    if (!n.isScalar()) fail(file, n, what + ": expected a number");
    try
    {
        const std::string s = n.as<std::string>();
        size_t used = 0;
        const double v = std::stod(s, &used);
        if (used != s.size() || !std::isfinite(v)) throw std::invalid_argument(s);
        return v;
    }
    catch (const std::exception&)
    {
        fail(file, n, what + ": expected a number");
    }
}

TPoint2D point(const std::string& file, const node_t& n, const std::string& what)
{
    if (!n.isSequence() || n.asSequence().size() != 2) fail(file, n, what + ": expected [x, y]");
    return {number(file, n.asSequence()[0], what), number(file, n.asSequence()[1], what)};
}

std::vector<TPoint2D> pointList(const std::string& file, const node_t& n, const std::string& what)
{
    if (!n.isSequence() || n.asSequence().empty())
        fail(file, n, what + ": expected a non-empty list of [x, y]");
    std::vector<TPoint2D> out;
    for (const auto& e : n.asSequence()) out.push_back(point(file, e, what));
    return out;
}

/** 0 if `text` is well-formed UTF-8, else the 1-based offset of the first bad byte. */
size_t firstNonUtf8Byte(const std::string& text)
{
    const auto* b = reinterpret_cast<const unsigned char*>(text.data());
    const size_t n = text.size();
    for (size_t i = 0; i < n;)
    {
        const unsigned c = b[i];
        size_t len = c < 0x80           ? 1
                     : (c >> 5) == 0x6  ? 2
                     : (c >> 4) == 0xE  ? 3
                     : (c >> 3) == 0x1E ? 4
                                        : 0;
        if (len == 0 || (len == 2 && c < 0xC2) || i + len > n) return i + 1;
        for (size_t k = 1; k < len; ++k)
            if ((b[i + k] & 0xC0) != 0x80) return i + 1;
        i += len;
    }
    return 0;
}

mrpt::containers::yaml parseYaml(const std::string& text, const std::string& name)
{
    // Checked here: the YAML parser's own error for it leaks memory (MRPT 2.5 with libfyaml 0.7),
    // and a file saved in another encoding deserves its own message.
    if (const size_t bad = firstNonUtf8Byte(text); bad)
        throw std::runtime_error(
            name + ":" +
            std::to_string(1 + std::count(text.begin(), text.begin() + bad - 1, '\n')) +
            ": not UTF-8 text (byte " + std::to_string(bad) + "): save the file as UTF-8");
    try
    {
        return mrpt::containers::yaml::FromText(text);
    }
    catch (const std::exception& e)
    {
        throw std::runtime_error(name + ": YAML syntax error: " + e.what());
    }
}

const node_t* child(const node_t& map, const std::string& key)
{
    if (!map.isMap()) return nullptr;
    for (const auto& [k, v] : map.asMap())
        if (k.as<std::string>() == key) return &v;
    return nullptr;
}

std::string readFile(const std::string& path)
{
    if (!mrpt::system::fileExists(path)) throw std::runtime_error(path + ": file not found");
    return mrpt::io::file_get_contents(path);
}
}  // namespace

ArrayGeometry loadArrayFile(const std::string& path)
{
    const auto doc = parseYaml(readFile(path), path);
    const node_t* elements = child(doc.node(), "elements");
    if (!elements) throw std::runtime_error(path + ": array file without 'elements'");
    return ArrayGeometry::fromElements(pointList(path, *elements, "elements"));
}

TransmitterMap TransmitterMap::fromYamlFile(const std::string& path)
{
    return fromYamlText(readFile(path), path, mrpt::system::extractFileDirectory(path));
}

TransmitterMap TransmitterMap::fromYamlText(
    const std::string& text, const std::string& name, const std::string& baseDir)
{
    const auto doc = parseYaml(text, name);
    const node_t* listPtr = child(doc.node(), "transmitters");
    if (!listPtr) throw std::runtime_error(name + ": expected a top-level 'transmitters:' list");
    const node_t& list = *listPtr;
    if (!list.isSequence()) fail(name, list, "transmitters: expected a list");

    static const std::set<std::string> allowed = {
        "name",           "mac",     "position", "yaw_deg",       "array",
        "array_elements", "channel", "streams",  "frame_rate_hz", "tx_power_dbm"};
    TransmitterMap map;
    size_t idx = 0;
    for (const node_t& e : list.asSequence())
    {
        const std::string where = "transmitters[" + std::to_string(idx++) + "]";
        if (!e.isMap()) fail(name, e, where + ": expected a map");
        const auto& m = e.asMap();
        for (const auto& [k, v] : m)
        {
            const auto key = k.as<std::string>();
            if (!allowed.count(key)) fail(name, v, where + ": unknown key '" + key + "'");
        }
        auto get = [&](const char* key) { return child(e, key); };
        KnownTransmitter t;
        const node_t* mac = get("mac");
        if (!mac) fail(name, e, where + ": missing 'mac'");
        const auto parsed = MacAddress::parse(mac->as<std::string>());
        if (!parsed)
            fail(name, *mac, where + ".mac: malformed MAC '" + mac->as<std::string>() + "'");
        t.mac = *parsed;
        t.name = get("name") ? get("name")->as<std::string>() : t.mac.asString();
        const node_t* pos = get("position");
        if (!pos) fail(name, e, where + ": missing 'position'");
        const auto p = point(name, *pos, where + ".position");
        const double yaw = get("yaw_deg") ? number(name, *get("yaw_deg"), where + ".yaw_deg") : 0;
        t.pose = mrpt::math::TPose2D(p.x, p.y, mrpt::DEG2RAD(yaw));
        if (get("array") && get("array_elements"))
            fail(name, e, where + ": give 'array' or 'array_elements', not both");
        if (const node_t* a = get("array"))
        {
            // Beside this file, else by name from the data folder (`ap-linear-4`).
            std::string path;
            try
            {
                path = config::resolveConfigPath(
                           a->as<std::string>(), baseDir.empty() ? "." : baseDir, "arrays",
                           where + ".array")
                           .path;
            }
            catch (const std::invalid_argument& ex)
            {
                fail(name, *a, ex.what());
            }
            t.array = loadArrayFile(path);
        }
        else if (const node_t* el = get("array_elements"))
            t.array = ArrayGeometry::fromElements(pointList(name, *el, where + ".array_elements"));
        else
            t.array = ArrayGeometry::fromElements({});
        try
        {
            map.add(t);
        }
        catch (const std::invalid_argument& ex)
        {
            fail(name, e, where + ": " + ex.what());
        }
    }
    return map;
}

std::string TransmitterMap::asYamlText() const
{
    std::ostringstream o;
    o.precision(9);
    o << "transmitters:\n";
    for (const auto& t : list_)
    {
        o << "  - name: " << t.name << "\n    mac: '" << t.mac.asString() << "'\n"
          << "    position: [" << t.pose.x << ", " << t.pose.y << "]\n"
          << "    yaw_deg: " << mrpt::RAD2DEG(t.pose.phi) << "\n    array_elements: [";
        for (size_t i = 0; i < t.array.elements.size(); ++i)
            o << (i ? ", " : "") << "[" << t.array.elements[i].x << ", " << t.array.elements[i].y
              << "]";
        o << "]\n";
    }
    return o.str();
}

void TransmitterMap::add(const KnownTransmitter& t)
{
    if (byMac_.count(t.mac)) throw std::invalid_argument("duplicate MAC " + t.mac.asString());
    if (byName_.count(t.name)) throw std::invalid_argument("duplicate name '" + t.name + "'");
    byMac_[t.mac] = int(list_.size());
    byName_[t.name] = int(list_.size());
    list_.push_back(t);
}

int TransmitterMap::indexOf(const MacAddress& mac) const
{
    const auto it = byMac_.find(mac);
    return it == byMac_.end() ? -1 : it->second;
}

const KnownTransmitter* TransmitterMap::find(const MacAddress& mac) const
{
    const int i = indexOf(mac);
    return i < 0 ? nullptr : &list_[size_t(i)];
}

const KnownTransmitter* TransmitterMap::findByText(const std::string& text) const
{
    if (const auto it = byName_.find(text); it != byName_.end()) return &list_[size_t(it->second)];
    if (const auto mac = MacAddress::parse(text)) return find(*mac);
    return nullptr;
}

void TransmitterMap::bounds(
    double margin, double& xmin, double& xmax, double& ymin, double& ymax) const
{
    xmin = ymin = 1e300;
    xmax = ymax = -1e300;
    for (const auto& t : list_)
    {
        xmin = std::min(xmin, t.pose.x), xmax = std::max(xmax, t.pose.x);
        ymin = std::min(ymin, t.pose.y), ymax = std::max(ymax, t.pose.y);
    }
    if (list_.empty()) xmin = xmax = ymin = ymax = 0;
    xmin -= margin, ymin -= margin, xmax += margin, ymax += margin;
}

}  // namespace mrpt_wifi::localization
