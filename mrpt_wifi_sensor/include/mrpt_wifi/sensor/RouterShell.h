/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/sensor/Subprocess.h>

#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** Why a router operation failed; the sensor reports it in its error state. */
enum class RouterErrorKind : uint8_t
{
    Unreachable,           //!< no route, refused, DNS, connect timeout
    AuthenticationFailed,  //!< key or password rejected
    HostKeyMismatch,       //!< unknown or changed host key (known_hosts honoured)
    Timeout,               //!< a remote command exceeded its time
    CommandMissing,        //!< wl / nexutil / makecsiparams not found: not a Nexmon firmware
    WrongFirmware,         //!< the tools ran but refused (no CSI support, bad ioctl)
    CommandFailed          //!< anything else that exited non-zero
};
const char* toString(RouterErrorKind k);

class RouterError : public std::runtime_error
{
public:
    RouterError(RouterErrorKind kind, const std::string& what)
        : std::runtime_error(std::string(toString(kind)) + ": " + what), kind_(kind)
    {
    }
    RouterErrorKind kind() const { return kind_; }

private:
    RouterErrorKind kind_;
};

/** Runs shell commands on the router. */
class RouterShell
{
public:
    virtual ~RouterShell() = default;
    /** Runs `command` in the router's shell; throws RouterError when the transport fails or
     * the command exits non-zero (the error says which). Returns stdout. */
    virtual std::string run(const std::string& command, double timeout_s) = 0;
    /** Human-readable destination, e.g. "admin@192.168.50.1:22" (never a password). */
    virtual std::string describe() const = 0;
};

struct SshOptions
{
    std::string host = "192.168.50.1";
    unsigned port = 22;
    std::string user = "admin";
    std::string identityFile;    //!< private key; empty: ssh's defaults
    std::string knownHostsFile;  //!< empty: ~/.ssh/known_hosts
    /** Accept and remember the host key of a router never seen before (never a changed one). */
    bool acceptNewHostKey = false;
    /** Name of an environment variable holding the password. The password reaches ssh only
     * through SSH_ASKPASS (our `mrpt-wifi-askpass`), never argv, logs or files. Empty: keys. */
    std::string passwordEnvVar;
    std::string askpassProgram;  //!< empty: mrpt-wifi-askpass beside the library, else PATH
    double connectTimeout_s = 5.0;
    /** Keep one remote shell open and send every command to it: a command then costs a
     * round trip through an existing session (milliseconds), not a new ssh channel and shell
     * (hundreds of milliseconds) — what makes channel switches fast. */
    bool persistentSession = true;
    std::string sshProgram = "ssh";
};

/** RouterShell over the system OpenSSH client. */
class SshRouterShell : public RouterShell
{
public:
    explicit SshRouterShell(SshOptions options);
    ~SshRouterShell() override;
    std::string run(const std::string& command, double timeout_s) override;
    std::string describe() const override;
    /** The ssh argv for a command (for tests: proves no secret is on the command line). */
    std::vector<std::string> sshArgv(const std::string& command) const;

private:
    struct Session;
    SshOptions options_;
    std::unique_ptr<Session> session_;
    uint64_t commandCounter_ = 0;
    std::map<std::string, std::string> askpassEnvironment() const;
    std::string runInSession(const std::string& command, double timeout_s);
    /** The RouterError of a failed command: ssh's own failures explained (explainSshFailure). */
    RouterError failureError(
        const std::string& command, const SubprocessResult& r, double timeout_s) const;
};

/** Classifies a failed ssh / remote command from its exit code and stderr. */
RouterErrorKind classifyRouterFailure(const SubprocessResult& r);

/** Why ssh itself failed (exit status 255), from everything it wrote on stderr, as one
 *  sentence naming the cause (connection refused, timed out, no route, unknown host name,
 *  authentication, unknown or changed host key, missing identity file, closed by the router)
 *  and what to check, with the .ini key / csi-router option to change. The cause is taken from
 *  the line that names it, not ssh's first line (often a warning such as "Identity file ...
 *  not accessible", which is added as a note). Never contains a password (ssh never prints
 *  one). */
std::string explainSshFailure(const std::string& sshStderr, const SshOptions& options);

}  // namespace mrpt_wifi
