/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <string>
#include <vector>

/** The emulated Asus RT-AC86U with Nexmon CSI firmware: router state, its command-line tools
 * (wl, nexutil, makecsiparams, insmod, rmmod, brctl) and the CSI data plane on loopback. */
namespace mrpt_wifi::emulator
{
/** A command line as a shell passes it: argv[0] is the tool name. */
using Argv = std::vector<std::string>;

/** What a command printed and returned, as a shell would see it. */
struct ToolResult
{
    int exitCode = 0;
    std::string out;  //!< stdout
    std::string err;  //!< stderr

    static ToolResult success(std::string out = {}) { return {0, std::move(out), {}}; }
    static ToolResult failure(std::string err, int exitCode = 1)
    {
        if (!err.empty() && err.back() != '\n') err += '\n';
        return {exitCode, {}, std::move(err)};
    }
};

/** Exit code of ssh when it cannot reach the host: what a shim returns while the emulated
 * router is rebooting or the emulator is not running. */
constexpr int kUnreachableExitCode = 255;

/** A POSIX getopt-like parser of short options ("-l34", "-l 34", "-br" grouping), enough for
 * the router tools, which are plain getopt programs. */
class ShortOptionParser
{
public:
    /** `spec` as for getopt(3): letters, a ':' after those that take a value. `args` excludes
     * the program name. */
    ShortOptionParser(const Argv& args, std::string spec);

    /** Next option: true with `option` (and `value` if it takes one). False at the end or on an
     * error (then error() is non-empty). Parsing stops at the first non-option ("--" too). */
    bool next(char& option, std::string& value);
    const std::string& error() const { return error_; }
    /** Arguments left after the options. */
    Argv remaining() const;

private:
    const Argv& args_;
    std::string spec_;
    size_t index_ = 0;    // argument being parsed
    size_t charPos_ = 0;  // position inside a grouped "-abc"
    std::string error_;
};

/** Parses an unsigned integer as strtol(…, 0) does (decimal, 0x hex, leading-0 octal), the
 * whole text; false if it is not one or exceeds `max`. */
bool parseUnsigned(const std::string& text, unsigned long max, unsigned long& out);

}  // namespace mrpt_wifi::emulator
