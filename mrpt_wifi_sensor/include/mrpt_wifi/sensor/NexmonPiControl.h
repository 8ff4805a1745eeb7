/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/sensor/NexmonRouterControl.h>
#include <mrpt_wifi/sensor/RouterShell.h>

#include <memory>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** Runs one program given as argv: on this machine (no shell) or on a remote host. */
class CommandRunner
{
public:
    virtual ~CommandRunner() = default;
    /** Returns stdout; throws RouterError (what failed, exit code, first stderr line). */
    virtual std::string run(const std::vector<std::string>& argv, double timeout_s) = 0;
    virtual std::string describe() const = 0;
};

/** Runs programs here with runSubprocess(): argv as given, no shell. `toolDir` (empty: $PATH)
 *  is where the programs are looked up. */
class LocalCommandRunner : public CommandRunner
{
public:
    explicit LocalCommandRunner(std::string toolDir = {}) : toolDir_(std::move(toolDir)) {}
    std::string run(const std::vector<std::string>& argv, double timeout_s) override;
    std::string describe() const override;

private:
    std::string toolDir_;
};

/** Runs programs through a RouterShell (ssh): argv joined with shellQuote(), so each argument
 *  reaches the program as one word whatever it holds. */
class ShellCommandRunner : public CommandRunner
{
public:
    ShellCommandRunner(std::shared_ptr<RouterShell> shell, std::string toolDir = {})
        : shell_(std::move(shell)), toolDir_(std::move(toolDir))
    {
    }
    std::string run(const std::vector<std::string>& argv, double timeout_s) override;
    std::string describe() const override { return shell_->describe(); }

private:
    std::shared_ptr<RouterShell> shell_;
    std::string toolDir_;
};

/** Where and how the Raspberry Pi's Nexmon CSI is set up (`pi_*` keys). */
struct PiSetupOptions
{
    std::string interface = "wlan0";        //!< pi_interface
    std::string monitorInterface = "mon0";  //!< pi_monitor_interface (empty: none)
    std::string toolDir;                    //!< pi_tool_dir: nexutil, makecsiparams, ip, iw
    double commandTimeout_s = 10.0;         //!< command_timeout

    /** Interface names must be Linux interface names without shell metacharacters
     *  (`[A-Za-z0-9_.-]`, 1..15 characters); the tool directory an absolute path of
     *  `[A-Za-z0-9_./+@%:,=-]`. Throws std::invalid_argument naming the key. */
    void validate() const;
};

/** The extraction settings the Pi's BCM43455c0 can do: 20/40/80 MHz on 5 GHz, 20 MHz on
 *  2.4 GHz; one core, one stream (masks 0x1); at most 4 MAC addresses. Throws
 *  std::invalid_argument naming the .ini key (`channel`, `core_mask`, `stream_mask`,
 *  `packet_mac_filter`). */
void validatePiExtraction(const CsiExtractionSettings& s);

/** Configures Nexmon CSI on a Raspberry Pi 3B+/4/400 (BCM43455c0), the steps of nexmon_csi's
 *  README, each as one program with its arguments:
 *  `ip link set wlan0 up`, `makecsiparams -c CH/BW -C 0x1 -N 0x1 [-m MACs] [-d D] [-b B]`,
 *  `nexutil -Iwlan0 -s500 -b -l34 -v<params>`, then (when a monitor interface is wanted)
 *  `iw dev wlan0 interface add mon0 type monitor` if `ip link show mon0` says there is none,
 *  and `ip link set mon0 up`. Locally (LocalCommandRunner) or over ssh (ShellCommandRunner on
 *  an SshRouterShell, the same transport, host-key and password handling as the router's). */
class NexmonPiControl
{
public:
    /** Throws std::invalid_argument if `options` fail PiSetupOptions::validate(). */
    NexmonPiControl(std::shared_ptr<CommandRunner> runner, PiSetupOptions options);

    /** Throws std::invalid_argument (bad settings, naming the key) or RouterError. */
    void configure(const CsiExtractionSettings& s);
    /** The programs configure() runs (the nexutil value as `<params>`; the monitor interface
     *  is added only if `ip link show` says it doesn't exist), for logs. */
    std::vector<std::vector<std::string>> configureCommands(const CsiExtractionSettings& s) const;
    std::string describe() const { return runner_->describe(); }

private:
    std::vector<std::string> makeCsiParamsArgv(const CsiExtractionSettings& s) const;
    std::shared_ptr<CommandRunner> runner_;
    PiSetupOptions options_;
};

}  // namespace mrpt_wifi
