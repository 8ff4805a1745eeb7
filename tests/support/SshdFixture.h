/* mrpt_wifi — a real OpenSSH server on 127.0.0.1 for tests. */
#pragma once

#include <mrpt_wifi/sensor/Subprocess.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <random>
#include <thread>

#include "TestSupport.h"

namespace mrpt_wifi::test
{
/** A free port of `type` on 127.0.0.1, below the kernel's ephemeral range: a port the kernel
 *  hands out (bind to 0) is free only until the next socket of any process asks for one, and a
 *  test's emulator sends from such sockets, so the program that binds it later could find it
 *  taken. A random port under the range (checked by binding it) is never handed out; bind to 0
 *  is the fallback. */
inline uint16_t freeLoopbackPort(int type = SOCK_STREAM)
{
    const auto tryBind = [type](uint16_t port) -> uint16_t
    {
        const int fd = ::socket(AF_INET, type, 0);
        if (fd < 0) return 0;
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        a.sin_port = htons(port);
        uint16_t got = 0;
        if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0)
        {
            socklen_t len = sizeof(a);
            ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
            got = ntohs(a.sin_port);
        }
        ::close(fd);
        return got;
    };
    int ephemeralLow = 32768;
    std::ifstream("/proc/sys/net/ipv4/ip_local_port_range") >> ephemeralLow;
    const int low = 10000, high = std::min(ephemeralLow, 65536) - 1;
    if (high > low)
    {
        std::mt19937 rng(std::random_device{}());
        std::uniform_int_distribution<int> pick(low, high);
        for (int attempt = 0; attempt < 200; ++attempt)
            if (const uint16_t p = tryBind(uint16_t(pick(rng)))) return p;
    }
    return tryBind(0);
}

/** Debian's sshd on 127.0.0.1 with a temporary host key and one authorised client key, for
 * the current user. `pathPrefix` goes first in the PATH of remote commands (command shims). */
class SshdFixture
{
public:
    explicit SshdFixture(const std::string& pathPrefix = "")
    {
        const auto keygen = [&](const std::string& file)
        {
            return runSubprocess(
                       {"ssh-keygen", "-q", "-t", "ed25519", "-N", "", "-f", dir_.file(file)}, 30)
                       .exitCode == 0;
        };
        if (!keygen("host_key") || !keygen("client_key") || !keygen("other_key")) return;
        std::filesystem::copy_file(dir_.file("client_key.pub"), dir_.file("authorized_keys"));
        std::filesystem::permissions(
            dir_.path(), std::filesystem::perms::owner_all, std::filesystem::perm_options::replace);
        port_ = freeLoopbackPort();
        const std::string path = (pathPrefix.empty() ? "" : pathPrefix + ":") +
                                 "/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin";
        std::ofstream(dir_.file("sshd_config"))
            << "ListenAddress 127.0.0.1\nPort " << port_ << "\nHostKey " << dir_.file("host_key")
            << "\nAuthorizedKeysFile " << dir_.file("authorized_keys") << "\nPidFile "
            << dir_.file("sshd.pid") << "\nStrictModes no\nUsePAM no\nPasswordAuthentication no\n"
            << "KbdInteractiveAuthentication no\nPermitRootLogin prohibit-password\n"
            << "SetEnv PATH=" << path << "\nLogLevel ERROR\nMaxStartups 50:30:100\n";
        std::ifstream hostPub(dir_.file("host_key.pub"));
        std::string type, key;
        hostPub >> type >> key;
        std::ofstream(dir_.file("known_hosts"))
            << "[127.0.0.1]:" << port_ << " " << type << " " << key << "\n";
        std::filesystem::create_directories("/run/sshd");  // privilege separation dir (root)

        pid_ = ::fork();
        if (pid_ == 0)
        {
            ::execl(
                "/usr/sbin/sshd", "/usr/sbin/sshd", "-D", "-e", "-f",
                dir_.file("sshd_config").c_str(), nullptr);
            ::_exit(127);
        }
        // Ready when it accepts connections (bounded wait).
        for (int i = 0; i < 100 && !ready_; ++i)
        {
            const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
            sockaddr_in a{};
            a.sin_family = AF_INET;
            a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
            a.sin_port = htons(port_);
            ready_ = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
            ::close(fd);
            if (!ready_) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
    }
    ~SshdFixture()
    {
        if (pid_ > 0)
        {
            ::kill(pid_, SIGTERM);
            ::waitpid(pid_, nullptr, 0);
        }
    }
    bool ready() const { return ready_; }
    uint16_t port() const { return port_; }
    std::string clientKey() const { return dir_.file("client_key"); }
    std::string otherKey() const { return dir_.file("other_key"); }
    std::string knownHosts() const { return dir_.file("known_hosts"); }
    std::string user() const
    {
        const passwd* pw = ::getpwuid(::getuid());
        return pw ? pw->pw_name : "root";
    }
    const TempDir& dir() const { return dir_; }

private:
    TempDir dir_;
    uint16_t port_ = 0;
    pid_t pid_ = -1;
    bool ready_ = false;
};

#define MRPT_WIFI_REQUIRE_SSHD(fixture) \
    ASSERT_TRUE((fixture).ready()) << "could not start /usr/sbin/sshd on 127.0.0.1"

}  // namespace mrpt_wifi::test
