/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/poses/CPose3D.h>

#include <chrono>
#include <exception>
#include <functional>
#include <string>
#include <vector>

/** Small pieces every mrpt_wifi command-line program shares. */
namespace mrpt_wifi::cli
{
/** An argv TCLAP can parse, in which the `count` tokens after `flag` are joined into one
 * (TCLAP takes one value per flag), so `--sensor-pose 0 0 0.3 90 0 0` works as documented. */
class JoinedArgv
{
public:
    JoinedArgv(int argc, char** argv, const std::string& flag, unsigned count);
    int argc() const { return int(pointers_.size()); }
    const char** argv() { return pointers_.data(); }

private:
    std::vector<std::string> args_;
    std::vector<const char*> pointers_;
};

/** Parses a TCLAP command line. MRPT's TCLAP returns false both after --help and after an
 * error (which it has printed): returns -1 to go on, else the exit code (0 or 1). */
template <class TclapCmdLine>
int parseCommandLine(TclapCmdLine& cmd, int argc, const char** argv)
{
    if (cmd.parse(argc, argv)) return -1;
    for (int i = 1; i < argc; ++i)
    {
        const std::string a = argv[i];
        if (a == "--help" || a == "-h" || a == "--version") return 0;
    }
    return 1;
}

/** Parses "x y z yaw pitch roll" (metres, degrees) into a pose; throws std::invalid_argument
 * naming `what` if it isn't six numbers. */
mrpt::poses::CPose3D poseFromText(const std::string& text, const std::string& what);

/** A one-line progress indicator on stderr, redrawn at most a few times a second. */
class Progress
{
public:
    explicit Progress(std::string label, bool enabled = true);
    void update(double fraction, const std::string& detail = {});
    void done(const std::string& detail = {});

private:
    std::string label_;
    bool enabled_;
    std::chrono::steady_clock::time_point start_, lastDraw_;
};

/** The message of an exception, without the banner and call-stack backtrace MRPT exceptions
 * carry (what a user should read); trailing white space trimmed. */
std::string exceptionMessage(const std::exception& e);

/** Loads an MRPT plugin library (`-p`); a path, as MRPT's own tools take it. Throws naming
 *  the library and the loader's reason when it cannot be loaded. */
void loadPlugin(const std::string& path);

/** Runs a program body, turning exceptions into a message on stderr and exit code 1. */
int runMain(const std::string& program, const std::function<int()>& body);

/** Exit status of a converter that finished the file but skipped malformed records (listed in
 *  its summary); 1 is a failure, 0 a clean conversion. */
constexpr int kExitRecordsSkipped = 3;

/** Exit statuses naming why a live program got no usable CSI (wifi-localize after
 *  no_csi_timeout_s; csi-router for the router and the data path). docs/troubleshooting.md
 *  lists them per program. */
constexpr int kExitRouterControlFailed = 4;  //!< ssh or a router command failed
constexpr int kExitNoDatagrams = 5;          //!< nothing arrived on the UDP port / source
constexpr int kExitNoMatchingFrames = 6;     //!< datagrams, but no CSI frame passed checks/filters
constexpr int kExitNoBearings = 7;           //!< CSI frames, but no bearing from them
constexpr int kExitNoMappedBearings =
    8;  //!< bearings, none the AP map can weigh (not its APs, or no weighed angle)

}  // namespace mrpt_wifi::cli
