/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/emulator/ToolResult.h>
#include <poll.h>

#include <chrono>
#include <functional>
#include <string>
#include <vector>

namespace mrpt_wifi::emulator
{
/** Environment variable that tells a shim where the emulator's socket is. */
constexpr const char* kSocketEnvironmentVariable = "RT_AC86U_EMULATOR_SOCKET";
/** Socket file name inside the state directory (the shims live in STATE_DIR/bin/). */
constexpr const char* kSocketFileName = "emulator.sock";
/** Names the emulator links to the shim in STATE_DIR/bin/. */
const std::vector<std::string>& shimToolNames();

/** Length-prefixed messages between a shim and the emulator over a Unix stream socket:
 * request  = "RTAC" u32 argc, then per argument u32 length + bytes;
 * response = "RTAC" i32 exit code, u32 length + stdout, u32 length + stderr (little-endian). */
namespace protocol
{
std::string encodeRequest(const Argv& argv);
/** True once `buffer` holds a whole request (decoded into `argv`); throws
 * std::invalid_argument for a malformed or oversized one. */
bool decodeRequest(const std::string& buffer, Argv& argv);
std::string encodeResponse(const ToolResult& r);
bool decodeResponse(const std::string& buffer, ToolResult& r);
}  // namespace protocol

/** The emulator's end: a non-blocking listening Unix socket served from the emulator's own
 * poll loop (single-threaded: the handler runs between two sends of the data plane). */
class ControlServer
{
public:
    using Handler = std::function<ToolResult(const Argv&)>;

    /** Creates and listens on `socketPath`. A stale socket file is replaced; if another
     * emulator answers on it, throws std::runtime_error. */
    ControlServer(const std::string& socketPath, Handler handler);
    ~ControlServer();
    ControlServer(const ControlServer&) = delete;
    ControlServer& operator=(const ControlServer&) = delete;

    /** Appends the descriptors to poll (the listening socket first, then the clients). */
    void appendPollFds(std::vector<pollfd>& fds) const;
    /** Handles the events of the descriptors appended by appendPollFds() starting at `first`. */
    void handleEvents(const std::vector<pollfd>& fds, size_t first);

    /** True while an answer is still being written (serve them before shutting down). */
    bool hasPendingAnswers() const;

    const std::string& path() const { return path_; }
    uint64_t requestsServed() const { return served_; }

private:
    struct Client
    {
        int fd = -1;
        std::string in, out;
        size_t written = 0;
        bool answered = false;
        std::chrono::steady_clock::time_point since;
    };
    void closeClient(Client& c);

    std::string path_;
    Handler handler_;
    int listenFd_ = -1;
    std::vector<Client> clients_;
    uint64_t served_ = 0;
};

/** The shim's end: sends `argv` to the emulator listening on `socketPath` and waits for the
 * answer. Throws std::runtime_error if it can't connect or gets no answer within timeout_s. */
ToolResult callEmulator(const std::string& socketPath, const Argv& argv, double timeout_s = 10.0);

/** Where a shim invoked as `argv0` finds the emulator socket: $RT_AC86U_EMULATOR_SOCKET if set,
 * else <directory of the invoked link>/../emulator.sock. A bare name (run through $PATH, as
 * an sshd's shell does) is looked up in `pathVariable` first. Empty if it can't tell. */
std::string findEmulatorSocket(
    const std::string& argv0, const char* environmentValue, const char* pathVariable);

}  // namespace mrpt_wifi::emulator
