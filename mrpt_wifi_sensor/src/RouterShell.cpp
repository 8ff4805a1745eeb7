/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <dlfcn.h>
#include <fcntl.h>
#include <mrpt_wifi/sensor/RouterShell.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>

extern char** environ;

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
    // POSIX shells exit 127 for a missing command; "wl: ... adapter not found" is not that.
    if (r.exitCode == 127 || contains(e, "command not found"))
        return RouterErrorKind::CommandMissing;
    if (contains(e, "ioctl") || contains(e, "Unsupported") || contains(e, "nexutil"))
        return RouterErrorKind::WrongFirmware;
    return RouterErrorKind::CommandFailed;
}

/** A remote `sh` reached through one ssh process: commands go to its stdin, each followed by
 * sentinel lines on stdout and stderr that carry the exit status. */
struct SshRouterShell::Session
{
    pid_t pid = -1;
    int in = -1, out = -1, err = -1;
    std::string outBuf, errBuf;

    ~Session() { close(); }
    void close()
    {
        for (int* fd : {&in, &out, &err})
            if (*fd >= 0) ::close(*fd), *fd = -1;
        if (pid > 0)
        {
            ::kill(pid, SIGTERM);
            ::waitpid(pid, nullptr, 0);
            pid = -1;
        }
    }
    /** Exit status of ssh if it has ended (then the session is unusable), else -2. */
    int exited()
    {
        int status = 0;
        if (pid > 0 && ::waitpid(pid, &status, WNOHANG) == pid)
        {
            pid = -1;
            return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        }
        return -2;
    }
};

SshRouterShell::SshRouterShell(SshOptions options) : options_(std::move(options))
{
    if (options_.askpassProgram.empty()) options_.askpassProgram = defaultAskpass();
}

SshRouterShell::~SshRouterShell() = default;

std::map<std::string, std::string> SshRouterShell::askpassEnvironment() const
{
    if (options_.passwordEnvVar.empty()) return {};
    const char* secret = std::getenv(options_.passwordEnvVar.c_str());
    if (!secret)
        throw RouterError(
            RouterErrorKind::AuthenticationFailed,
            "environment variable " + options_.passwordEnvVar + " (router password) is not set");
    return {
        {"SSH_ASKPASS", options_.askpassProgram},
        {"SSH_ASKPASS_REQUIRE", "force"},
        {"DISPLAY", ":0"},
        {"MRPT_WIFI_ASKPASS_SECRET", secret}};
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
    a.push_back(options_.user + "@" + options_.host);
    a.push_back(command);
    return a;
}

std::string SshRouterShell::run(const std::string& command, double timeout_s)
{
    if (options_.persistentSession) return runInSession(command, timeout_s);
    const auto r = runSubprocess(sshArgv(command), timeout_s, askpassEnvironment());
    if (r.exitCode == 0 && !r.timedOut) return r.out;
    const auto kind = classifyRouterFailure(r);
    std::string detail = firstLine(r.err.empty() ? r.out : r.err);
    if (r.timedOut) detail = "no answer within " + std::to_string(timeout_s) + " s";
    throw RouterError(
        kind,
        describe() + ": '" + command + "' (exit " + std::to_string(r.exitCode) + "): " + detail);
}

std::string SshRouterShell::runInSession(const std::string& command, double timeout_s)
{
    const auto fail = [&](const SubprocessResult& r)
    {
        session_.reset();
        const auto kind = classifyRouterFailure(r);
        std::string detail = firstLine(r.err.empty() ? r.out : r.err);
        if (r.timedOut) detail = "no answer within " + std::to_string(timeout_s) + " s";
        return RouterError(
            kind, describe() + ": '" + command + "' (exit " + std::to_string(r.exitCode) +
                      "): " + detail);
    };

    if (!session_)
    {
        auto env = askpassEnvironment();
        auto s = std::make_unique<Session>();
        int inPipe[2], outPipe[2], errPipe[2];
        if (::pipe2(inPipe, O_CLOEXEC) || ::pipe2(outPipe, O_CLOEXEC) ||
            ::pipe2(errPipe, O_CLOEXEC))
            throw std::runtime_error("pipe2 failed");
        auto argv = sshArgv("sh");
        std::vector<char*> args;
        for (auto& a : argv) args.push_back(a.data());
        args.push_back(nullptr);
        std::vector<std::string> envStrings;
        for (char** e = environ; *e; ++e) envStrings.emplace_back(*e);
        for (const auto& [k, v] : env) envStrings.push_back(k + "=" + v);
        std::vector<char*> envp;
        for (auto& e : envStrings) envp.push_back(e.data());
        envp.push_back(nullptr);
        s->pid = ::fork();
        if (s->pid == 0)
        {
            ::setsid();  // no controlling terminal: ssh asks askpass, never a tty
            ::dup2(inPipe[0], STDIN_FILENO);
            ::dup2(outPipe[1], STDOUT_FILENO);
            ::dup2(errPipe[1], STDERR_FILENO);
            ::execvpe(args[0], args.data(), envp.data());
            ::_exit(127);
        }
        ::close(inPipe[0]), ::close(outPipe[1]), ::close(errPipe[1]);
        s->in = inPipe[1], s->out = outPipe[0], s->err = errPipe[0];
        ::fcntl(s->out, F_SETFL, O_NONBLOCK);
        ::fcntl(s->err, F_SETFL, O_NONBLOCK);
        session_ = std::move(s);
    }

    auto& s = *session_;
    const std::string sentinel = "__mrpt_wifi_end_" + std::to_string(++commandCounter_);
    // stdin of the command is /dev/null so it can't swallow the commands that follow.
    const std::string script = "{ " + command + "\n} </dev/null; echo \"" + sentinel +
                               " $?\"; echo " + sentinel + " 1>&2\n";
    ::signal(SIGPIPE, SIG_IGN);
    if (::write(s.in, script.data(), script.size()) != ssize_t(script.size()))
    {
        SubprocessResult r;
        r.exitCode = s.exited();
        r.err = s.errBuf;
        throw fail(r);
    }

    const auto start = std::chrono::steady_clock::now();
    const auto deadline = start + std::chrono::duration<double>(timeout_s);
    const std::string outMark = sentinel + " ", errMark = sentinel + "\n";
    size_t outAt = std::string::npos, errAt = std::string::npos;
    char buf[4096];
    while (outAt == std::string::npos || errAt == std::string::npos ||
           s.outBuf.find('\n', outAt) == std::string::npos)
    {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0)
        {
            SubprocessResult r;
            r.timedOut = true;
            throw fail(r);
        }
        pollfd fds[2] = {{s.out, POLLIN, 0}, {s.err, POLLIN, 0}};
        ::poll(fds, 2, int(std::min<long>(left.count(), 50)));
        bool eof = false;
        for (int i = 0; i < 2; ++i)
        {
            if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            const ssize_t n = ::read(fds[i].fd, buf, sizeof(buf));
            if (n > 0)
                (i == 0 ? s.outBuf : s.errBuf).append(buf, size_t(n));
            else if (n == 0)
                eof = true;
        }
        if (outAt == std::string::npos) outAt = s.outBuf.find(outMark);
        if (errAt == std::string::npos) errAt = s.errBuf.find(errMark);
        int code = s.exited();
        if (eof || code != -2)
        {
            // ssh ended: it could not connect or authenticate, the router dropped us, or the
            // command ended the remote shell itself.
            if (code == -2 && s.pid > 0)
            {
                int status = 0;
                ::waitpid(s.pid, &status, 0);
                s.pid = -1;
                code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
            }
            SubprocessResult r;
            r.exitCode = code;
            r.err = s.errBuf;
            throw fail(r);
        }
    }
    const std::string out = s.outBuf.substr(0, outAt);
    const int exitCode = std::stoi(s.outBuf.substr(outAt + outMark.size()));
    const std::string err = s.errBuf.substr(0, errAt);
    s.outBuf.erase(0, s.outBuf.find('\n', outAt) + 1);
    s.errBuf.erase(0, errAt + errMark.size());
    if (exitCode == 0) return out;
    SubprocessResult r;
    r.exitCode = exitCode;
    r.out = out;
    r.err = err;
    const auto kind = classifyRouterFailure(r);
    throw RouterError(
        kind, describe() + ": '" + command + "' (exit " + std::to_string(exitCode) +
                  "): " + firstLine(err.empty() ? out : err));
}

}  // namespace mrpt_wifi
