/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/core/exceptions.h>
#include <mrpt/system/os.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::cli
{
JoinedArgv::JoinedArgv(int argc, char** argv, const std::string& flag, unsigned count)
    : args_(argv, argv + argc)
{
    auto& args = args_;
    for (size_t i = 0; i < args.size(); ++i)
    {
        if (args[i] != flag || i + 1 >= args.size()) continue;
        // Join tokens until the value holds `count` numbers: `--flag "a b c"` (one quoted
        // token) is complete already and must not swallow the options after it.
        const auto words = [](const std::string& t)
        {
            std::istringstream in(t);
            size_t n = 0;
            for (std::string w; in >> w;) ++n;
            return n;
        };
        size_t have = words(args[i + 1]), next = i + 2;
        while (have < count && next < args.size())
        {
            args[i + 1] += " " + args[next];
            have += words(args[next]);
            args.erase(args.begin() + long(next));
        }
    }
    for (const auto& a : args_) pointers_.push_back(a.c_str());
}

mrpt::poses::CPose3D poseFromText(const std::string& text, const std::string& what)
{
    std::istringstream in(text);
    double v[6];
    for (double& x : v)
        if (!(in >> x))
            throw std::invalid_argument(
                what + ": expected six numbers 'x y z yaw pitch roll' (m, deg), got '" + text +
                "'");
    std::string rest;
    if (in >> rest) throw std::invalid_argument(what + ": more than six numbers in '" + text + "'");
    return mrpt::poses::CPose3D(
        v[0], v[1], v[2], mrpt::DEG2RAD(v[3]), mrpt::DEG2RAD(v[4]), mrpt::DEG2RAD(v[5]));
}

Progress::Progress(std::string label, bool enabled)
    : label_(std::move(label)),
      enabled_(enabled && isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now())
{
}

void Progress::update(double fraction, const std::string& detail)
{
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - lastDraw_ < std::chrono::milliseconds(200) && fraction < 1.0) return;
    lastDraw_ = now;
    std::fprintf(stderr, "\r%s %5.1f%% %s   ", label_.c_str(), 100.0 * fraction, detail.c_str());
    std::fflush(stderr);
}

void Progress::done(const std::string& detail)
{
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (enabled_) std::fprintf(stderr, "\r%s 100.0%% %s   \n", label_.c_str(), detail.c_str());
    std::fprintf(stderr, "%s: done in %.2f s\n", label_.c_str(), secs);
}

std::string exceptionMessage(const std::exception& e)
{
    std::string msg = e.what();
    if (const auto trace = msg.find("Call stack backtrace"); trace != std::string::npos)
        msg.erase(trace);
    for (const char* banner : {"==== MRPT exception ====\n", "Message:  "})
        if (const auto b = msg.find(banner); b != std::string::npos)
            msg.erase(b, std::strlen(banner));
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
    return msg;
}

void loadPlugin(const std::string& path)
{
    std::string err;
    if (!mrpt::system::loadPluginModules(path, err))
        throw std::runtime_error("cannot load plugin '" + path + "': " + err);
}

int runMain(const std::string& program, const std::function<int()>& body)
{
    try
    {
        return body();
    }
    catch (const std::exception& e)
    {
        std::cerr << program << ": error: " << exceptionMessage(e) << std::endl;
        return 1;
    }
    catch (...)  // not derived from std::exception: still an error message, not an abort
    {
        std::cerr << program << ": error: unexpected exception (not a std::exception)" << std::endl;
        return 1;
    }
}

}  // namespace mrpt_wifi::cli
