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

std::string explainSshFailure(const std::string& sshStderr, const SshOptions& o)
{
    const std::string where = o.host + " port " + std::to_string(o.port);
    const std::string knownHosts =
        o.knownHostsFile.empty() ? std::string("~/.ssh/known_hosts") : o.knownHostsFile;
    // ssh's lines, without the "Warning: Identity file" note and blank lines.
    std::vector<std::string> lines;
    std::string identityNote;
    for (size_t at = 0; at < sshStderr.size();)
    {
        size_t end = sshStderr.find('\n', at);
        if (end == std::string::npos) end = sshStderr.size();
        std::string line = sshStderr.substr(at, end - at);
        at = end + 1;
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
        if (line.empty()) continue;
        if (contains(line, "Identity file") && contains(line, "not accessible"))
        {
            identityNote = line.substr(line.find("Identity file"));
            if (identityNote.back() == '.') identityNote.pop_back();
        }
        else
            lines.push_back(line);
    }
    const auto said = [&](const char* what)
    {
        return std::any_of(
            lines.begin(), lines.end(), [&](const std::string& l) { return contains(l, what); });
    };
    std::string cause;
    if (said("Connection refused"))
        cause = "connection refused: nothing accepts ssh on " + where +
                " (is the router's SSH server enabled - Administration > System > Enable SSH - "
                "and is login_port / --port the port it listens on?)";
    else if (said("timed out"))
        cause = "connection timed out: no answer from " + where + " within " +
                std::to_string(int(std::max(1.0, o.connectTimeout_s))) +
                " s (router off or still booting, login_host / --host wrong, this computer on "
                "another network, or a firewall dropping the connection)";
    else if (said("No route to host") || said("Network is unreachable") || said("Host is down"))
        cause = "no route to " + o.host +
                ": this computer has no network path to the router (cable or WiFi link, this "
                "computer's address on the router's network, login_host / --host)";
    else if (
        said("Could not resolve hostname") || said("Name or service not known") ||
        said("Temporary failure in name resolution"))
        cause = "cannot resolve the host name '" + o.host +
                "' (login_host / --host: give the router's IP address, e.g. 192.168.50.1)";
    else if (said("REMOTE HOST IDENTIFICATION HAS CHANGED"))
        cause = "the router's host key changed since it was stored in " + knownHosts +
                " (a re-flashed or reset router: remove the old key with ssh-keygen -R '[" +
                o.host + "]:" + std::to_string(o.port) + "' -f " + knownHosts +
                "; another machine answering at this address: stop and check)";
    else if (said("Host key verification failed") || said("host key is known"))
        cause = "the router's host key is not in " + knownHosts + " (check it once with ssh -p " +
                std::to_string(o.port) + " " + o.user + "@" + o.host +
                ", or trust a router never seen before with login_accept_new_host_key = true / "
                "--accept-new-host-key)";
    else if (said("Permission denied") || said("Too many authentication failures"))
        cause = "authentication failed: the router rejected " +
                (o.passwordEnvVar.empty()
                     ? (o.identityFile.empty() ? std::string("this user's ssh keys")
                                               : "the key " + o.identityFile) +
                           " (put its .pub in the router's Administration > System > Authorized "
                           "Keys; login_identity_file / --identity; login_user / --user is '" +
                           o.user + "')"
                     : "the password in $" + o.passwordEnvVar + " for user '" + o.user +
                           "' (login_password_env / --password-env, login_user / --user)");
    else if (
        said("Connection closed") || said("Connection reset") ||
        said("kex_exchange_identification"))
        cause =
            "the router closed the connection before login (its ssh server refused this "
            "client: too many sessions, or ssh not allowed from this network - check the "
            "router's SSH settings)";
    else if (!lines.empty())
        cause = lines.back();
    else if (!identityNote.empty())
        cause = "ssh failed";
    else
        cause = "ssh failed without a message (is '" + o.sshProgram + "' the OpenSSH client?)";
    if (!identityNote.empty())
        cause += "; also: " + identityNote +
                 " (login_identity_file / --identity names a key file that does not exist)";
    return cause;
}

RouterErrorKind classifyRouterFailure(const SubprocessResult& r)
{
    if (r.timedOut) return RouterErrorKind::Timeout;
    const std::string& e = r.err;
    if (r.exitCode == 255)
    {
        if (contains(e, "Host key verification failed") ||
            contains(e, "REMOTE HOST IDENTIFICATION") || contains(e, "host key is known"))
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
    /** After ssh ended or broke the pipe: the rest of what it wrote on stderr (the line with
     *  the cause may come after a warning), until end of file or at most `limit_ms`. */
    void drainStderr(int limit_ms = 1000)
    {
        const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(limit_ms);
        char buf[4096];
        while (err >= 0 && std::chrono::steady_clock::now() < until)
        {
            pollfd fd = {err, POLLIN, 0};
            if (::poll(&fd, 1, 50) <= 0) continue;
            const ssize_t n = ::read(err, buf, sizeof(buf));
            if (n <= 0) break;
            errBuf.append(buf, size_t(n));
        }
    }
    /** Exit status of ssh, waiting for it to end. */
    int waitExit()
    {
        const int code = exited();
        if (code != -2 || pid <= 0) return code;
        int status = 0;
        ::waitpid(pid, &status, 0);
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
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
    throw failureError(command, r, timeout_s);
}

RouterError SshRouterShell::failureError(
    const std::string& command, const SubprocessResult& r, double timeout_s) const
{
    const auto kind = classifyRouterFailure(r);
    if (r.timedOut)
        return RouterError(
            kind, describe() + ": '" + command + "': no answer within " +
                      std::to_string(timeout_s) + " s");
    // ssh's own failure (not the remote command's): say why and what to check.
    if (r.exitCode == 255)
        return RouterError(
            kind, describe() + ": " + explainSshFailure(r.err, options_) + " (ssh exit 255 on '" +
                      command + "')");
    return RouterError(
        kind, describe() + ": '" + command + "' (exit " + std::to_string(r.exitCode) +
                  "): " + firstLine(r.err.empty() ? r.out : r.err));
}

std::string SshRouterShell::runInSession(const std::string& command, double timeout_s)
{
    const auto fail = [&](const SubprocessResult& r)
    {
        session_.reset();
        return failureError(command, r, timeout_s);
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
        s.drainStderr();
        SubprocessResult r;
        r.exitCode = s.waitExit();
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
            s.drainStderr();
            if (code == -2) code = s.waitExit();
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
