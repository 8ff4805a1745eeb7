/* mrpt_wifi — runs the RT-AC86U emulator as a child process for tests. */
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "TestSupport.h"

namespace mrpt_wifi::test
{
/** `rt-ac86u-emulator` sending to 127.0.0.1:port, its state (socket, tool links) in a temporary
 * folder; always bounded by --duration and stopped with SIGTERM when the object goes. */
class EmulatorProcess
{
public:
    EmulatorProcess(
        const std::vector<std::string>& extraArgs, uint16_t udpPort, double maxSeconds = 60)
    {
        std::vector<std::string> args = {
            binDir() + "/rt-ac86u-emulator",
            "--port",
            std::to_string(udpPort),
            "--dest",
            "127.0.0.1",
            "--state-dir",
            stateDir(),
            "--duration",
            std::to_string(maxSeconds),
            "--status-period",
            "1"};
        args.insert(args.end(), extraArgs.begin(), extraArgs.end());
        pid_ = ::fork();
        if (pid_ == 0)
        {
            const int log = ::open(logFile().c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            ::dup2(log, STDOUT_FILENO);
            ::dup2(log, STDERR_FILENO);
            std::vector<char*> argv;
            for (auto& a : args) argv.push_back(a.data());
            argv.push_back(nullptr);
            ::execv(argv[0], argv.data());
            ::_exit(127);
        }
        // Ready when its control socket exists (bounded wait).
        for (int i = 0; i < 200 && !std::filesystem::exists(stateDir() + "/emulator.sock"); ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    ~EmulatorProcess() { stop(); }
    void stop()
    {
        if (pid_ <= 0) return;
        ::kill(pid_, SIGTERM);
        ::waitpid(pid_, nullptr, 0);
        pid_ = -1;
    }
    bool ready() const { return std::filesystem::exists(stateDir() + "/emulator.sock"); }
    std::string stateDir() const { return dir_.file("state"); }
    std::string toolsDir() const { return stateDir() + "/bin"; }
    std::string logFile() const { return dir_.file("emulator.log"); }
    std::string log() const { return readFile(logFile()); }

private:
    TempDir dir_;
    pid_t pid_ = -1;
};

/** Whether a UDP socket of this machine is bound to `port` (any address; /proc/net/udp and
 *  udp6), polled until `timeout`: a receiver is listening before the emulator streams to it. */
inline bool waitForUdpListener(uint16_t port, std::chrono::milliseconds timeout)
{
    const auto bound = [port]
    {
        for (const char* table : {"/proc/net/udp", "/proc/net/udp6"})
        {
            std::ifstream f(table);
            std::string line;
            std::getline(f, line);  // header
            while (std::getline(f, line))
            {
                std::istringstream row(line);
                std::string slot, local;
                row >> slot >> local;  // "0100007F:5C1E": the port in hex after the colon
                const auto colon = local.rfind(':');
                if (colon != std::string::npos &&
                    std::stoul(local.substr(colon + 1), nullptr, 16) == port)
                    return true;
            }
        }
        return false;
    };
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!bound())
    {
        if (std::chrono::steady_clock::now() >= deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    return true;
}

}  // namespace mrpt_wifi::test
