/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include "YamlReader.h"

#include <mrpt_wifi/sim/Scenario.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace mrpt_wifi::sim::detail
{
std::shared_ptr<YamlDocument> YamlDocument::parse(const std::string& text, const std::string& name)
{
    auto doc = std::make_shared<YamlDocument>();
    doc->fileName = name;
    try
    {
        doc->root = mrpt::containers::yaml::FromText(text);
    }
    catch (const std::exception& e)
    {
        // MRPT's message carries a backtrace; keep its first meaningful line.
        std::string msg = e.what();
        const auto pos = msg.find("Message:");
        if (pos != std::string::npos) msg = msg.substr(pos + 8);
        const auto eol = msg.find('\n');
        if (eol != std::string::npos) msg = msg.substr(0, eol);
        while (!msg.empty() && msg.front() == ' ') msg.erase(msg.begin());
        throw ScenarioError(name, 0, "", "YAML syntax error: " + msg);
    }
    return doc;
}

std::shared_ptr<YamlDocument> YamlDocument::load(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw ScenarioError(path, 0, "", "cannot open file");
    std::stringstream ss;
    ss << f.rdbuf();
    return parse(ss.str(), path);
}

int YamlDocument::lineOf(std::string path) const
{
    for (;;)
    {
        const auto it = lineOfPath.find(path);
        if (it != lineOfPath.end()) return it->second;
        if (path.empty()) return 0;
        const auto cut = path.find_last_of(".[");
        path = cut == std::string::npos ? std::string() : path.substr(0, cut);
    }
}

YamlNode::YamlNode(
    std::shared_ptr<YamlDocument> doc, const node_t* node, std::string path, int line)
    : doc_(std::move(doc)), node_(node), path_(std::move(path)), line_(line)
{
    doc_->lineOfPath.emplace(path_, line_);
}

YamlNode YamlNode::root(const std::shared_ptr<YamlDocument>& doc)
{
    const auto& n = doc->root.node();
    return YamlNode(doc, &n, "", n.marks.line + 1);
}

void YamlNode::fail(const std::string& message) const
{
    throw ScenarioError(doc_->fileName, line_, path_, message);
}

namespace
{
std::string keyText(const mrpt::containers::yaml::node_t& k)
{
    try
    {
        return k.as<std::string>();
    }
    catch (const std::exception&)
    {
        return "<non-text key>";
    }
}
std::string join(const std::string& parent, const std::string& key)
{
    return parent.empty() ? key : parent + "." + key;
}
}  // namespace

void YamlNode::allowOnly(std::initializer_list<const char*> allowed) const
{
    if (isNull()) return;  // "key:" with nothing under it: all defaults
    if (!isMap()) fail("expected a map of keys");
    for (const auto& [k, v] : node_->asMap())
    {
        const std::string key = keyText(k);
        bool ok = false;
        for (const char* a : allowed) ok = ok || key == a;
        if (ok) continue;
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        throw ScenarioError(
            doc_->fileName, k.marks.line + 1, join(path_, key),
            "unknown key '" + key + "' (allowed here: " + list + ")");
    }
}

bool YamlNode::has(const std::string& key) const
{
    if (!isMap()) return false;
    for (const auto& kv : node_->asMap())
        if (keyText(kv.first) == key) return true;
    return false;
}

std::optional<YamlNode> YamlNode::get(const std::string& key) const
{
    if (!isMap()) return std::nullopt;
    for (const auto& [k, v] : node_->asMap())
        if (keyText(k) == key)
        {
            // A value on its own lines (map, list) reports the key's line: that is what a
            // person looks for.
            const int line = (v.isMap() || v.isSequence() ? k.marks.line : v.marks.line) + 1;
            return YamlNode(doc_, &v, join(path_, key), line);
        }
    return std::nullopt;
}

YamlNode YamlNode::operator[](const std::string& key) const
{
    if (!isMap()) fail("expected a map with key '" + key + "'");
    auto n = get(key);
    if (!n) fail("missing required key '" + key + "'");
    return *n;
}

size_t YamlNode::size() const
{
    if (!isSequence()) fail("expected a list");
    return node_->asSequence().size();
}

YamlNode YamlNode::at(size_t i) const
{
    const auto& seq = node_->asSequence();
    const auto& n = seq.at(i);
    return YamlNode(doc_, &n, path_ + "[" + std::to_string(i) + "]", n.marks.line + 1);
}

std::string YamlNode::scalarText() const
{
    if (!isScalar()) fail("expected a single value, found " + node_->typeName());
    try
    {
        return node_->as<std::string>();
    }
    catch (const std::exception&)
    {
        // Built in code rather than parsed: numbers are stored as numbers.
        std::ostringstream ss;
        ss.precision(17);
        ss << node_->as<double>();
        return ss.str();
    }
}

std::string YamlNode::asString() const
{
    return scalarText();
}

double YamlNode::asDouble() const
{
    const std::string s = scalarText();
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v))
        fail("expected a number, found '" + s + "'");
    return v;
}

long long YamlNode::asInteger() const
{
    const std::string s = scalarText();
    errno = 0;
    char* end = nullptr;
    const long long v = std::strtoll(s.c_str(), &end, 0);
    if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE)
        fail("expected an integer, found '" + s + "'");
    return v;
}

unsigned YamlNode::asUnsigned(unsigned maxValue) const
{
    const long long v = asInteger();
    if (v < 0 || static_cast<unsigned long long>(v) > maxValue)
        fail(
            "expected an integer in [0, " + std::to_string(maxValue) + "], found " +
            std::to_string(v));
    return static_cast<unsigned>(v);
}

bool YamlNode::asBool() const
{
    const std::string s = scalarText();
    if (s == "true" || s == "True" || s == "yes" || s == "on" || s == "1") return true;
    if (s == "false" || s == "False" || s == "no" || s == "off" || s == "0") return false;
    fail("expected true or false, found '" + s + "'");
}

mrpt::math::TPoint2D YamlNode::asPoint2D() const
{
    if (!isSequence() || size() != 2) fail("expected a point [x, y] in metres");
    return {at(0).asDouble(), at(1).asDouble()};
}

std::complex<double> YamlNode::asComplex() const
{
    if (isScalar()) return {asDouble(), 0.0};
    allowOnly({"magnitude", "phase_deg"});
    const double mag = (*this)["magnitude"].asDouble();
    const double phase = doubleOr("phase_deg", 0.0) * M_PI / 180.0;
    return std::polar(mag, phase);
}

double YamlNode::doubleOr(const std::string& key, double def) const
{
    const auto n = get(key);
    return n ? n->asDouble() : def;
}

unsigned YamlNode::unsignedOr(const std::string& key, unsigned def, unsigned maxValue) const
{
    const auto n = get(key);
    return n ? n->asUnsigned(maxValue) : def;
}

bool YamlNode::boolOr(const std::string& key, bool def) const
{
    const auto n = get(key);
    return n ? n->asBool() : def;
}

std::string YamlNode::stringOr(const std::string& key, const std::string& def) const
{
    const auto n = get(key);
    return n ? n->asString() : def;
}

}  // namespace mrpt_wifi::sim::detail
