/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * rt-ac86u-shim: the router's command-line tools for the RT-AC86U emulator. Installed as links
 * named wl, nexutil, makecsiparams, insmod, rmmod, lsmod, brctl, ifconfig, ip, iw, usleep and
 * emulator-ctl (the emulator creates them in STATE_DIR/bin/); the link's name picks the tool.
 * (ip and iw are the Raspberry Pi's, for `--device raspberry-pi`.) The
 * command line goes to the emulator over its Unix socket; its stdout, stderr and exit code become
 * the shim's. */
#include <mrpt_wifi/emulator/ControlSocket.h>
#include <mrpt_wifi/emulator/CsiParams.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>

using namespace mrpt_wifi::emulator;

namespace
{
std::string baseName(const std::string& p)
{
    const auto slash = p.find_last_of('/');
    return slash == std::string::npos ? p : p.substr(slash + 1);
}

int finish(const ToolResult& r)
{
    std::fwrite(r.out.data(), 1, r.out.size(), stdout);
    std::fwrite(r.err.data(), 1, r.err.size(), stderr);
    std::fflush(stdout);
    return r.exitCode < 0 || r.exitCode > 255 ? 1 : r.exitCode;
}

constexpr unsigned long kMaxUsleep_us = 60'000'000;

constexpr const char* kUsage =
    "Usage: rt-ac86u-shim [--socket PATH] TOOL [ARGS...]\n"
    "   or: TOOL [ARGS...] through a link named wl, nexutil, makecsiparams, insmod, rmmod,\n"
    "       lsmod, brctl, ifconfig, ip, iw, usleep or emulator-ctl (STATE_DIR/bin/ of the\n"
    "       emulator; ip and iw are the emulated Raspberry Pi's).\n"
    "The emulator's socket: --socket, else $RT_AC86U_EMULATOR_SOCKET, else\n"
    "<directory of the link>/../emulator.sock.\n";
}  // namespace

int main(int argc, char** argv)
{
    const std::string invokedAs = argc > 0 ? argv[0] : "rt-ac86u-shim";
    std::string tool = baseName(invokedAs);
    Argv args(argv + (argc > 0 ? 1 : 0), argv + argc);
    std::string socket;
    bool direct = false;
    if (tool == "rt-ac86u-shim")
    {
        direct = true;
        if (!args.empty() && args[0] == "--socket")
        {
            if (args.size() < 2) return finish(ToolResult::failure(kUsage, 2));
            socket = args[1];
            args.erase(args.begin(), args.begin() + 2);
        }
        if (args.empty() || args[0] == "--help" || args[0] == "-h")
            return finish(
                args.empty() ? ToolResult::failure(kUsage, 2) : ToolResult::success(kUsage));
        tool = args[0];
        args.erase(args.begin());
    }

    // A pure function of its arguments: no need to bother the emulator (same code either way).
    if (tool == "makecsiparams") return finish(makeCsiParams(args));
    // BusyBox's usleep, which the router has and Debian doesn't (transmitter loops use it).
    if (tool == "usleep")
    {
        unsigned long us = 0;
        if (args.size() != 1 || !parseUnsigned(args[0], kMaxUsleep_us, us))
            return finish(ToolResult::failure("Usage: usleep MICROSECONDS (at most 60 s)"));
        std::this_thread::sleep_for(std::chrono::microseconds(us));
        return 0;
    }

    if (socket.empty())
        socket = findEmulatorSocket(
            direct ? std::string() : invokedAs, std::getenv(kSocketEnvironmentVariable),
            std::getenv("PATH"));
    if (socket.empty())
        return finish(ToolResult::failure(
            tool + ": cannot tell where the RT-AC86U emulator is: set " +
                kSocketEnvironmentVariable + " or run the tool through STATE_DIR/bin/",
            kUnreachableExitCode));
    try
    {
        Argv command{tool};
        command.insert(command.end(), args.begin(), args.end());
        return finish(callEmulator(socket, command, 15.0));
    }
    catch (const std::exception& e)
    {
        return finish(ToolResult::failure(tool + ": " + e.what(), kUnreachableExitCode));
    }
}
