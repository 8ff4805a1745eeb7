/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <stdexcept>
#include <string>

namespace mrpt_wifi::localization
{
/** Whether `text` is one finite number, optionally followed by a comment (`;`, `#` or `//`).
 *  MRPT's read_double() takes "abc" and "" as 0, "1.5x" as 1.5 and accepts "nan" and "inf":
 *  a typo would silently become another setting. */
inline bool isIniNumber(const std::string& text)
{
    const char* s = text.c_str();
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(s, &end);
    if (end == s || errno == ERANGE || !std::isfinite(v)) return false;
    while (*end == ' ' || *end == '\t' || *end == '\r') ++end;
    return *end == '\0' || *end == ';' || *end == '#' || (end[0] == '/' && end[1] == '/');
}

/** Throws std::invalid_argument naming the section, the key and its text for each of `keys`
 *  present in `[section]` whose value is not a finite number (isIniNumber()). */
inline void requireIniNumbers(
    const mrpt::config::CConfigFileBase& c, const std::string& section,
    std::initializer_list<const char*> keys)
{
    for (const char* k : keys)
    {
        if (!c.keyExists(section, k)) continue;
        const std::string v = c.read_string(section, k, "");
        if (!isIniNumber(v))
            throw std::invalid_argument(
                "[" + section + "] " + k + " = '" + v + "': expected a finite number");
    }
}

/** The same for switches: true/false, yes/no or 1/0, any case (MRPT reads any other text as
 *  false: "on", a typo, or "true ; comment"). */
inline void requireIniBools(
    const mrpt::config::CConfigFileBase& c, const std::string& section,
    std::initializer_list<const char*> keys)
{
    for (const char* k : keys)
    {
        if (!c.keyExists(section, k)) continue;
        const std::string text = c.read_string(section, k, "");
        std::string v = text;
        while (!v.empty() && (v.back() == ' ' || v.back() == '\t' || v.back() == '\r'))
            v.pop_back();
        for (auto& ch : v) ch = char(std::tolower(static_cast<unsigned char>(ch)));
        if (v != "true" && v != "false" && v != "yes" && v != "no" && v != "1" && v != "0")
            throw std::invalid_argument(
                "[" + section + "] " + k + " = '" + text + "': expected true or false");
    }
}

}  // namespace mrpt_wifi::localization
