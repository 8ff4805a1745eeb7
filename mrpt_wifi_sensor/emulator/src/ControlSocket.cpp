/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/emulator/ControlSocket.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace mrpt_wifi::emulator
{
namespace
{
constexpr char kMagic[4] = {'R', 'T', 'A', 'C'};
constexpr uint32_t kMaxArguments = 1024;
constexpr size_t kMaxMessageBytes = 1 << 20;
constexpr double kClientIdleLimit_s = 5.0;  // a silent client is dropped after this

void putU32(std::string& s, uint32_t v)
{
    for (int i = 0; i < 4; ++i) s += char(uint8_t(v >> (8 * i)));
}
bool getU32(const std::string& s, size_t& pos, uint32_t& v)
{
    if (pos + 4 > s.size()) return false;
    v = 0;
    for (int i = 0; i < 4; ++i) v |= uint32_t(uint8_t(s[pos + size_t(i)])) << (8 * i);
    pos += 4;
    return true;
}
bool getBlob(const std::string& s, size_t& pos, std::string& out)
{
    uint32_t len = 0;
    size_t p = pos;
    if (!getU32(s, p, len)) return false;
    if (len > kMaxMessageBytes) throw std::invalid_argument("oversized field");
    if (p + len > s.size()) return false;
    out = s.substr(p, len);
    pos = p + len;
    return true;
}
bool checkMagic(const std::string& s)
{
    if (s.size() < 4) return false;
    if (std::memcmp(s.data(), kMagic, 4) != 0) throw std::invalid_argument("bad magic");
    return true;
}

sockaddr_un unixAddress(const std::string& path)
{
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    if (path.size() >= sizeof(a.sun_path))
        throw std::runtime_error(
            "socket path '" + path + "' is too long for a Unix socket (max " +
            std::to_string(sizeof(a.sun_path) - 1) + " bytes): use a shorter --state-dir");
    std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
    return a;
}

bool isExecutableFile(const std::string& p)
{
    struct stat st
    {
    };
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
}
}  // namespace

const std::vector<std::string>& shimToolNames()
{
    static const std::vector<std::string> names = {
        "wl",    "nexutil",  "makecsiparams", "insmod",       "rmmod", "lsmod",
        "brctl", "ifconfig", "usleep",        "emulator-ctl", "ip",    "iw"};
    return names;
}

// ----------------------------------------------------------------------------------- protocol
namespace protocol
{
std::string encodeRequest(const Argv& argv)
{
    std::string s(kMagic, 4);
    putU32(s, uint32_t(argv.size()));
    for (const auto& a : argv)
    {
        putU32(s, uint32_t(a.size()));
        s += a;
    }
    return s;
}

bool decodeRequest(const std::string& buffer, Argv& argv)
{
    if (buffer.size() > kMaxMessageBytes) throw std::invalid_argument("request too large");
    if (!checkMagic(buffer)) return false;
    size_t pos = 4;
    uint32_t argc = 0;
    if (!getU32(buffer, pos, argc)) return false;
    if (argc == 0 || argc > kMaxArguments) throw std::invalid_argument("bad argument count");
    Argv out;
    for (uint32_t i = 0; i < argc; ++i)
    {
        std::string a;
        if (!getBlob(buffer, pos, a)) return false;
        out.push_back(std::move(a));
    }
    if (pos != buffer.size()) throw std::invalid_argument("trailing bytes");
    argv = std::move(out);
    return true;
}

std::string encodeResponse(const ToolResult& r)
{
    std::string s(kMagic, 4);
    putU32(s, uint32_t(r.exitCode));
    putU32(s, uint32_t(r.out.size()));
    s += r.out;
    putU32(s, uint32_t(r.err.size()));
    s += r.err;
    return s;
}

bool decodeResponse(const std::string& buffer, ToolResult& r)
{
    if (!checkMagic(buffer)) return false;
    size_t pos = 4;
    uint32_t code = 0;
    ToolResult out;
    if (!getU32(buffer, pos, code) || !getBlob(buffer, pos, out.out) ||
        !getBlob(buffer, pos, out.err))
        return false;
    out.exitCode = int(int32_t(code));
    r = std::move(out);
    return true;
}
}  // namespace protocol

// ------------------------------------------------------------------------------------ server
ControlServer::ControlServer(const std::string& socketPath, Handler handler)
    : path_(socketPath), handler_(std::move(handler))
{
    const sockaddr_un addr = unixAddress(path_);
    struct stat st
    {
    };
    if (::lstat(path_.c_str(), &st) == 0)
    {
        if (!S_ISSOCK(st.st_mode))
            throw std::runtime_error("'" + path_ + "' exists and is not a socket");
        // Someone listening there? Then another emulator owns this state directory.
        const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
        const bool alive =
            probe >= 0 &&
            ::connect(probe, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) == 0;
        if (probe >= 0) ::close(probe);
        if (alive)
            throw std::runtime_error(
                "another emulator is already serving '" + path_ + "' (use another --state-dir)");
        ::unlink(path_.c_str());
    }
    listenFd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (listenFd_ < 0)
        throw std::runtime_error(std::string("cannot create Unix socket: ") + std::strerror(errno));
    if (::bind(listenFd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0 ||
        ::listen(listenFd_, 16) != 0)
    {
        const std::string why = std::strerror(errno);
        ::close(listenFd_);
        throw std::runtime_error("cannot listen on '" + path_ + "': " + why);
    }
    ::chmod(path_.c_str(), 0600);  // the user's own shells (and sshd sessions) only
}

ControlServer::~ControlServer()
{
    for (auto& c : clients_) closeClient(c);
    if (listenFd_ >= 0)
    {
        ::close(listenFd_);
        ::unlink(path_.c_str());
    }
}

void ControlServer::closeClient(Client& c)
{
    if (c.fd >= 0) ::close(c.fd);
    c.fd = -1;
}

bool ControlServer::hasPendingAnswers() const
{
    return std::any_of(
        clients_.begin(), clients_.end(), [](const Client& c) { return c.fd >= 0 && c.answered; });
}

void ControlServer::appendPollFds(std::vector<pollfd>& fds) const
{
    fds.push_back({listenFd_, POLLIN, 0});
    for (const auto& c : clients_) fds.push_back({c.fd, short(c.answered ? POLLOUT : POLLIN), 0});
}

void ControlServer::handleEvents(const std::vector<pollfd>& fds, size_t first)
{
    const auto now = std::chrono::steady_clock::now();
    for (size_t i = 0; i < clients_.size() && first + 1 + i < fds.size(); ++i)
    {
        Client& c = clients_[i];
        const short ev = fds[first + 1 + i].revents;
        if (!c.answered && (ev & (POLLIN | POLLHUP | POLLERR)))
        {
            char buf[4096];
            const ssize_t n = ::recv(c.fd, buf, sizeof(buf), 0);
            if (n <= 0)
            {
                if (n == 0 || (errno != EAGAIN && errno != EINTR)) closeClient(c);
                continue;
            }
            c.in.append(buf, size_t(n));
            Argv argv;
            bool complete = false;
            try
            {
                complete = protocol::decodeRequest(c.in, argv);
            }
            catch (const std::exception& e)
            {
                c.out = protocol::encodeResponse(ToolResult::failure(
                    std::string("emulator: malformed request: ") + e.what(), 2));
                c.answered = true;
            }
            if (complete)
            {
                ToolResult r;
                try
                {
                    r = handler_(argv);
                }
                catch (const std::exception& e)
                {
                    r = ToolResult::failure(
                        std::string("emulator: internal error: ") + e.what(), 2);
                }
                c.out = protocol::encodeResponse(r);
                c.answered = true;
                ++served_;
            }
        }
        else if (c.answered && (ev & (POLLOUT | POLLHUP | POLLERR)))
        {
            const ssize_t n =
                ::send(c.fd, c.out.data() + c.written, c.out.size() - c.written, MSG_NOSIGNAL);
            if (n > 0) c.written += size_t(n);
            if (n < 0 && errno != EAGAIN && errno != EINTR)
                closeClient(c);
            else if (c.written == c.out.size())
                closeClient(c);
        }
        if (c.fd >= 0 && std::chrono::duration<double>(now - c.since).count() > kClientIdleLimit_s)
            closeClient(c);
    }
    clients_.erase(
        std::remove_if(clients_.begin(), clients_.end(), [](const Client& c) { return c.fd < 0; }),
        clients_.end());

    if (first < fds.size() && (fds[first].revents & POLLIN))
        for (;;)
        {
            const int fd = ::accept4(listenFd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
            if (fd < 0) break;
            Client c;
            c.fd = fd;
            c.since = now;
            clients_.push_back(std::move(c));
        }
}

// ------------------------------------------------------------------------------------ client
ToolResult callEmulator(const std::string& socketPath, const Argv& argv, double timeout_s)
{
    const sockaddr_un addr = unixAddress(socketPath);
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
    struct Closer
    {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0)
        throw std::runtime_error(
            "cannot reach the RT-AC86U emulator at '" + socketPath + "': " + std::strerror(errno));
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    auto waitFor = [&](short events)
    {
        const double left =
            std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
        pollfd p{fd, events, 0};
        if (left <= 0 || ::poll(&p, 1, int(left * 1000) + 1) <= 0)
            throw std::runtime_error(
                "no answer from the RT-AC86U emulator within " + std::to_string(timeout_s) + " s");
    };
    const std::string request = protocol::encodeRequest(argv);
    for (size_t sent = 0; sent < request.size();)
    {
        waitFor(POLLOUT);
        const ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
        if (n < 0 && errno != EINTR && errno != EAGAIN)
            throw std::runtime_error(std::string("send to emulator: ") + std::strerror(errno));
        if (n > 0) sent += size_t(n);
    }
    std::string response;
    ToolResult r;
    for (;;)
    {
        waitFor(POLLIN);
        char buf[8192];
        const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
        if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
        if (n <= 0) break;
        response.append(buf, size_t(n));
        if (protocol::decodeResponse(response, r)) return r;
    }
    throw std::runtime_error("the RT-AC86U emulator closed the connection without an answer");
}

std::string findEmulatorSocket(
    const std::string& argv0, const char* environmentValue, const char* pathVariable)
{
    if (environmentValue && *environmentValue) return environmentValue;
    std::string invoked = argv0;
    if (invoked.find('/') == std::string::npos)
    {
        // Run through $PATH: find the link the shell found (first match, as the shell does).
        invoked.clear();
        const std::string path = pathVariable ? pathVariable : "";
        size_t start = 0;
        while (start <= path.size())
        {
            const size_t colon = std::min(path.find(':', start), path.size());
            const std::string dir = colon > start ? path.substr(start, colon - start) : ".";
            start = colon + 1;
            if (isExecutableFile(dir + "/" + argv0))
            {
                invoked = dir + "/" + argv0;
                break;
            }
        }
        if (invoked.empty()) return {};
    }
    // The link's own directory, not its target's: STATE_DIR/bin/wl → STATE_DIR/emulator.sock.
    const std::string dir = invoked.substr(0, invoked.find_last_of('/'));
    return (dir.empty() ? std::string("/") : dir) + "/../" + kSocketFileName;
}

}  // namespace mrpt_wifi::emulator
