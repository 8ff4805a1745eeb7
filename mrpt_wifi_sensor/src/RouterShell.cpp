/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <dlfcn.h>
#include <mrpt_wifi/sensor/RouterShell.h>

#include <cstdlib>
#include <filesystem>

namespace mrpt_wifi
{
namespace
{
bool contains(const std::string& s, const char* what)
{
    return s.find(what) != std::string::npos;
}

/** mrpt-wifi-askpass installed beside this library (build tree: ../bin; install: ../bin). */
std::string defaultAskpass()
{
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&defaultAskpass), &info) && info.dli_fname)
    {
        const auto libDir = std::filesystem::path(info.dli_fname).parent_path();
        for (const auto& candidate :
             {libDir / "../bin/mrpt-wifi-askpass", libDir / "mrpt-wifi-askpass"})
            if (std::filesystem::exists(candidate))
                return std::filesystem::canonical(candidate).string();
    }
    return "mrpt-wifi-askpass";
}

std::string firstLine(const std::string& s)
{
    const auto end = s.find('\n');
    return s.substr(0, end);
}
}  // namespace

const char* toString(RouterErrorKind k)
{
    switch (k)
    {
        case RouterErrorKind::Unreachable:
            return "router unreachable";
        case RouterErrorKind::AuthenticationFailed:
            return "authentication failed";
        case RouterErrorKind::HostKeyMismatch:
            return "host key not trusted";
        case RouterErrorKind::Timeout:
            return "router command timed out";
        case RouterErrorKind::CommandMissing:
            return "command missing on router";
        case RouterErrorKind::WrongFirmware:
            return "firmware refused";
        case RouterErrorKind::CommandFailed:
            return "router command failed";
    }
    return "router error";
}

RouterErrorKind classifyRouterFailure(const SubprocessResult& r)
{
    if (r.timedOut) return RouterErrorKind::Timeout;
    const std::string& e = r.err;
    if (r.exitCode == 255)
    {
        if (contains(e, "Host key verification failed") ||
            contains(e, "REMOTE HOST IDENTIFICATION"))
            return RouterErrorKind::HostKeyMismatch;
        if (contains(e, "Permission denied") || contains(e, "Too many authentication"))
            return RouterErrorKind::AuthenticationFailed;
        return RouterErrorKind::Unreachable;
    }
    if (r.exitCode == 127 || contains(e, "not found")) return RouterErrorKind::CommandMissing;
    if (contains(e, "ioctl") || contains(e, "Unsupported") || contains(e, "nexutil"))
        return RouterErrorKind::WrongFirmware;
    return RouterErrorKind::CommandFailed;
}

SshRouterShell::SshRouterShell(SshOptions options) : options_(std::move(options))
{
    if (options_.askpassProgram.empty()) options_.askpassProgram = defaultAskpass();
    if (options_.multiplex)
    {
        std::string tmpl =
            (std::filesystem::temp_directory_path() / "mrpt_wifi_ssh_XXXXXX").string();
        if (mkdtemp(tmpl.data())) controlDir_ = tmpl;  // 0700: the socket is as private as a key
    }
}

SshRouterShell::~SshRouterShell()
{
    if (controlDir_.empty()) return;
    // Close the shared connection, then its folder.
    auto argv = sshArgv("");
    argv.pop_back();
    argv.insert(argv.end() - 1, {"-O", "exit"});
    try
    {
        runSubprocess(argv, 2.0);
    }
    catch (...)
    {
    }
    std::error_code ec;
    std::filesystem::remove_all(controlDir_, ec);
}

std::string SshRouterShell::describe() const
{
    return options_.user + "@" + options_.host + ":" + std::to_string(options_.port);
}

std::vector<std::string> SshRouterShell::sshArgv(const std::string& command) const
{
    const bool password = !options_.passwordEnvVar.empty();
    std::vector<std::string> a = {options_.sshProgram, "-T", "-p", std::to_string(options_.port)};
    const auto opt = [&](const std::string& o) { a.insert(a.end(), {"-o", o}); };
    opt("ConnectTimeout=" + std::to_string(int(std::max(1.0, options_.connectTimeout_s))));
    opt("ServerAliveInterval=5");
    opt("ServerAliveCountMax=2");
    opt(std::string("StrictHostKeyChecking=") + (options_.acceptNewHostKey ? "accept-new" : "yes"));
    if (!options_.knownHostsFile.empty()) opt("UserKnownHostsFile=" + options_.knownHostsFile);
    if (!options_.identityFile.empty())
    {
        a.insert(a.end(), {"-i", options_.identityFile});
        opt("IdentitiesOnly=yes");
    }
    if (password)
    {
        opt("BatchMode=no");
        opt("NumberOfPasswordPrompts=1");
        opt("PreferredAuthentications=password,keyboard-interactive");
    }
    else
        opt("BatchMode=yes");
    if (!controlDir_.empty())
    {
        opt("ControlMaster=auto");
        opt("ControlPath=" + controlDir_ + "/cm-%C");
        opt("ControlPersist=30");
    }
    a.push_back(options_.user + "@" + options_.host);
    a.push_back(command);
    return a;
}

std::string SshRouterShell::run(const std::string& command, double timeout_s)
{
    std::map<std::string, std::string> env;
    if (!options_.passwordEnvVar.empty())
    {
        const char* secret = std::getenv(options_.passwordEnvVar.c_str());
        if (!secret)
            throw RouterError(
                RouterErrorKind::AuthenticationFailed, "environment variable " +
                                                           options_.passwordEnvVar +
                                                           " (router password) is not set");
        env = {
            {"SSH_ASKPASS", options_.askpassProgram},
            {"SSH_ASKPASS_REQUIRE", "force"},
            {"DISPLAY", ":0"},
            {"MRPT_WIFI_ASKPASS_SECRET", secret}};
    }
    const auto r = runSubprocess(sshArgv(command), timeout_s, env);
    if (r.exitCode == 0 && !r.timedOut) return r.out;
    const auto kind = classifyRouterFailure(r);
    std::string detail = firstLine(r.err.empty() ? r.out : r.err);
    if (r.timedOut) detail = "no answer within " + std::to_string(timeout_s) + " s";
    throw RouterError(
        kind,
        describe() + ": '" + command + "' (exit " + std::to_string(r.exitCode) + "): " + detail);
}

}  // namespace mrpt_wifi
