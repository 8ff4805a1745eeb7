/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <fcntl.h>
#include <mrpt_wifi/sensor/Subprocess.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

extern char** environ;

namespace mrpt_wifi
{
SubprocessResult runSubprocess(
    const std::vector<std::string>& argv, double timeout_s,
    const std::map<std::string, std::string>& extraEnv)
{
    if (argv.empty()) throw std::invalid_argument("runSubprocess: empty argv");
    int outPipe[2], errPipe[2];
    if (::pipe2(outPipe, O_CLOEXEC) != 0)
        throw std::runtime_error("pipe2: " + std::string(std::strerror(errno)));
    if (::pipe2(errPipe, O_CLOEXEC) != 0)
    {
        ::close(outPipe[0]), ::close(outPipe[1]);
        throw std::runtime_error("pipe2: " + std::string(std::strerror(errno)));
    }

    // Build argv/envp before fork: the child must only call async-signal-safe functions.
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    std::vector<std::string> envStrings;
    for (char** e = environ; *e; ++e)
    {
        const std::string kv = *e;
        const auto eq = kv.find('=');
        if (eq != std::string::npos && extraEnv.count(kv.substr(0, eq))) continue;
        envStrings.push_back(kv);
    }
    for (const auto& [k, v] : extraEnv) envStrings.push_back(k + "=" + v);
    std::vector<char*> envp;
    for (auto& s : envStrings) envp.push_back(s.data());
    envp.push_back(nullptr);

    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error("fork: " + std::string(std::strerror(errno)));
    if (pid == 0)
    {
        ::setpgid(0, 0);  // own process group, so a timeout kills its children too
        const int devNull = ::open("/dev/null", O_RDONLY);
        ::dup2(devNull, STDIN_FILENO);
        ::dup2(outPipe[1], STDOUT_FILENO);
        ::dup2(errPipe[1], STDERR_FILENO);
        ::execvpe(args[0], args.data(), envp.data());
        const char msg[] = "exec failed\n";
        [[maybe_unused]] auto w = ::write(STDERR_FILENO, msg, sizeof(msg) - 1);
        ::_exit(127);
    }
    ::setpgid(pid, pid);
    ::close(outPipe[1]);
    ::close(errPipe[1]);

    SubprocessResult r;
    pollfd fds[2] = {{outPipe[0], POLLIN, 0}, {errPipe[0], POLLIN, 0}};
    std::string* sinks[2] = {&r.out, &r.err};
    const auto deadline = start + std::chrono::duration<double>(timeout_s);
    char buf[4096];
    int status = 0;
    bool exited = false;
    // Read until the child has exited and its pipes are drained. A grandchild that keeps a
    // pipe open (ssh's ControlPersist master) must not make us wait, so the loop ends on the
    // child's exit rather than on end-of-file.
    for (;;)
    {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (!exited && left.count() <= 0)
        {
            r.timedOut = true;
            break;
        }
        const int waitMs = exited ? 0 : int(std::min<long>(left.count(), 20));
        const int ready = ::poll(fds, 2, waitMs);
        bool readSomething = false;
        for (int i = 0; ready > 0 && i < 2; ++i)
        {
            if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            const ssize_t n = ::read(fds[i].fd, buf, sizeof(buf));
            if (n > 0)
            {
                sinks[i]->append(buf, size_t(n));
                readSomething = true;
            }
            else
            {
                ::close(fds[i].fd);
                fds[i].fd = -1;
            }
        }
        if (fds[0].fd < 0 && fds[1].fd < 0 && exited) break;
        if (exited && !readSomething) break;  // drained what the child left behind
        if (!exited && ::waitpid(pid, &status, WNOHANG) == pid) exited = true;
    }
    if (r.timedOut)
    {
        ::kill(-pid, SIGTERM);
        for (int i = 0; i < 20 && ::waitpid(pid, &status, WNOHANG) == 0; ++i) ::usleep(10000);
        if (::waitpid(pid, &status, WNOHANG) == 0)
        {
            ::kill(-pid, SIGKILL);
            ::waitpid(pid, &status, 0);
        }
        exited = true;
    }
    for (auto& f : fds)
        if (f.fd >= 0) ::close(f.fd);
    if (!exited) ::waitpid(pid, &status, 0);
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
}

}  // namespace mrpt_wifi
