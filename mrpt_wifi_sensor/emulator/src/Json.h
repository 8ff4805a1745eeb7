/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace mrpt_wifi::emulator::detail
{
/** A JSON string literal, escaped. */
inline std::string jsonQuote(const std::string& s)
{
    std::string out = "\"";
    for (const char c : s)
    {
        switch (c)
        {
            case '"':
                out += "\\\"";
                break;
            case '\\':
                out += "\\\\";
                break;
            case '\n':
                out += "\\n";
                break;
            case '\t':
                out += "\\t";
                break;
            default:
                if (uint8_t(c) < 0x20)
                {
                    char buf[8];
                    std::snprintf(buf, sizeof(buf), "\\u%04x", unsigned(uint8_t(c)));
                    out += buf;
                }
                else
                    out += c;
        }
    }
    return out + "\"";
}

inline std::string jsonNumber(double v)
{
    if (!std::isfinite(v)) return "null";
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.6g", v);
    return buf;
}

/** Builds one JSON object, key by key, in insertion order. */
class JsonObject
{
public:
    JsonObject& raw(const std::string& key, const std::string& json)
    {
        if (!body_.empty()) body_ += ", ";
        body_ += jsonQuote(key) + ": " + json;
        return *this;
    }
    JsonObject& str(const std::string& key, const std::string& v) { return raw(key, jsonQuote(v)); }
    JsonObject& num(const std::string& key, double v) { return raw(key, jsonNumber(v)); }
    JsonObject& uint(const std::string& key, uint64_t v) { return raw(key, std::to_string(v)); }
    JsonObject& integer(const std::string& key, int64_t v) { return raw(key, std::to_string(v)); }
    JsonObject& boolean(const std::string& key, bool v) { return raw(key, v ? "true" : "false"); }
    std::string json() const { return "{" + body_ + "}"; }

private:
    std::string body_;
};

inline std::string jsonArray(const std::vector<std::string>& items)
{
    std::string out = "[";
    for (size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + items[i];
    return out + "]";
}

}  // namespace mrpt_wifi::emulator::detail
