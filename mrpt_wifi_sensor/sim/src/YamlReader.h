/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// Strict reading of YAML documents for scenario and array files: every access knows its key
// path and line, so errors say where they are; unknown keys are errors, not silently ignored.

#include <mrpt/containers/yaml.h>
#include <mrpt/math/TPoint2D.h>

#include <complex>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace mrpt_wifi::sim::detail
{
/** The document being read: its name and the line of every key path seen. */
struct YamlDocument
{
    std::string fileName;
    mrpt::containers::yaml root;
    std::map<std::string, int> lineOfPath;  // 1-based

    /** Parses text; syntax errors become ScenarioError(fileName, ...). */
    static std::shared_ptr<YamlDocument> parse(const std::string& text, const std::string& name);
    static std::shared_ptr<YamlDocument> load(const std::string& path);

    /** Line of a key path, or of its closest recorded ancestor (0 if none). */
    int lineOf(std::string path) const;
};

/** A node of the document with its key path ("transmitters[2].channel"). */
class YamlNode
{
public:
    using node_t = mrpt::containers::yaml::node_t;

    YamlNode(std::shared_ptr<YamlDocument> doc, const node_t* node, std::string path, int line);
    static YamlNode root(const std::shared_ptr<YamlDocument>& doc);

    const std::string& path() const { return path_; }
    int line() const { return line_; }
    const YamlDocument& document() const { return *doc_; }

    [[noreturn]] void fail(const std::string& message) const;

    bool isMap() const { return node_->isMap(); }
    bool isSequence() const { return node_->isSequence(); }
    bool isScalar() const { return node_->isScalar(); }
    bool isNull() const { return node_->isNullNode(); }

    // ---- maps
    /** Fails on the first key not in `allowed`, naming it and listing the allowed ones. */
    void allowOnly(std::initializer_list<const char*> allowed) const;
    bool has(const std::string& key) const;
    /** Required key. */
    YamlNode operator[](const std::string& key) const;
    std::optional<YamlNode> get(const std::string& key) const;

    // ---- sequences
    size_t size() const;
    YamlNode at(size_t i) const;

    // ---- scalars (strict: "12abc" is an error, not 12)
    std::string asString() const;
    double asDouble() const;
    long long asInteger() const;
    unsigned asUnsigned(unsigned maxValue = ~0u) const;
    bool asBool() const;
    /** [x, y] */
    mrpt::math::TPoint2D asPoint2D() const;
    /** A real number, or {magnitude, phase_deg}. */
    std::complex<double> asComplex() const;

    // ---- optional keys with defaults
    double doubleOr(const std::string& key, double def) const;
    unsigned unsignedOr(const std::string& key, unsigned def, unsigned maxValue = ~0u) const;
    bool boolOr(const std::string& key, bool def) const;
    std::string stringOr(const std::string& key, const std::string& def) const;

private:
    std::string scalarText() const;

    std::shared_ptr<YamlDocument> doc_;
    const node_t* node_ = nullptr;
    std::string path_;
    int line_ = 0;
};

}  // namespace mrpt_wifi::sim::detail
