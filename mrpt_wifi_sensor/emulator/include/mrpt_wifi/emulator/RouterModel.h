/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/emulator/CsiParams.h>
#include <mrpt_wifi/emulator/ToolResult.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi::emulator
{
/** Which wireless driver module the router kernel has loaded. */
enum class DriverModule : uint8_t
{
    Stock = 0,  //!< after boot: Asus' dhd; no CSI, nexutil ioctls fail
    None,       //!< after `rmmod dhd`: no wireless interfaces at all
    NexmonCsi   //!< after `insmod …/dhd.ko`: the patched firmware, CSI available
};
const char* toString(DriverModule m);

/** The device the model plays. */
enum class RouterKind : uint8_t
{
    RtAc86u = 0,  //!< Asus RT-AC86U (BCM4366c0), stock dhd until the Nexmon module is loaded
    RaspberryPi   //!< Raspberry Pi 3B+/4 (BCM43455c0) with the Nexmon CSI firmware installed
};
const char* toString(RouterKind k);

/** One access point as `wl scanresults` reports it. */
struct ScanEntry
{
    std::string ssid;
    MacAddress bssid;
    Chanspec chanspec;
    int rssi_dBm = -127;
    int noise_dBm = -92;
};

/** Physical timings and strictness of the emulated router. */
struct RouterTiming
{
    /** Data-plane silence after the radio is tuned to another chanspec (PLL settling,
     * calibration). Real 4366c0 retunes take a few tens of ms. */
    double retuneDelay_s = 0.020;
    /** Time a `wl scan` takes; `wl scanresults` before that fails with "Not Ready". */
    double scanDuration_s = 1.0;
    /** While scanning the radio visits other channels: CSI of that interface stops. */
    bool scanInterruptsCsi = true;
    /** Time after a reboot during which the router answers nothing (exit 255). */
    double rebootDuration_s = 1.0;
    /** CSI of frames not addressed to the router needs `wl monitor 1`, as on the real router. */
    bool requireMonitorMode = true;
};

/** State of one wireless interface (eth6 = 5 GHz, eth5 = 2.4 GHz). */
struct WirelessInterface
{
    std::string name;
    WifiBand band = WifiBand::Band5G;
    bool present = true;  //!< false while the driver module is unloaded
    bool up = true;
    bool radioOn = true;
    bool monitor = false;  //!< router: `wl monitor 1`; Pi: its monitor interface exists, up
    bool bridged = true;
    bool dualBand = false;         //!< Pi's wlan0: the CSI parameters pick the band
    std::string monitorInterface;  //!< Pi: `iw dev wlan0 interface add NAME type monitor`
    bool monitorInterfaceUp =
        false;  //!< member of br0: CSI datagrams only reach the LAN through it
    std::string country = "US";
    std::string rate5G = "auto", rate2G4 = "auto";  //!< `wl 5g_rate` / `wl 2g_rate` settings
    Chanspec chanspec;
    std::optional<CsiParams> csi;  //!< last parameters nexutil -s500 applied
    double retuneUntil_s = -std::numeric_limits<double>::infinity();
    double scanUntil_s = -std::numeric_limits<double>::infinity();
    bool scanDone = false;  //!< a scan ran and its results are available
    std::vector<ScanEntry> scanResults;
    uint64_t framesInjected = 0;  //!< nexutil -s505 (transmitter / beacon mode)
    size_t lastInjectedLength = 0;
    double lastInjection_s = -std::numeric_limits<double>::infinity();
};

/** Why an interface's CSI does not reach the host. */
enum class SilenceReason : uint8_t
{
    None = 0,
    Rebooting,
    StockFirmware,
    ModuleNotLoaded,
    InterfaceDown,
    RadioOff,
    NotBridged,
    MonitorOff,
    CsiNotConfigured,
    CsiDisabled,
    Retuning,
    Scanning
};
const char* toString(SilenceReason r);

/** An interface whose CSI reaches the host now, and with which settings. */
struct ActiveCapture
{
    std::string interfaceName;
    Chanspec chanspec;  //!< where the radio is tuned
    CsiParams csi;
};

/** The router's state machine and its command-line tools, without any I/O: commands are
 * argv vectors, time is seconds on the emulator's wall clock.
 *
 * RouterKind::RaspberryPi plays a Pi with nexmon_csi instead: one dual-band `wlan0` (the
 * patched firmware is always loaded), the tools `nexutil`, `makecsiparams`, `ifconfig`, `ip`
 * (`ip link set|show`) and `iw` (`iw dev wlan0 interface add mon0 type monitor`, `iw dev mon0
 * del`); CSI flows once wlan0 is up, `nexutil -s500` set the parameters (which also tune the
 * radio) and the monitor interface is up.
 *
 * After a (re)boot the stock module is loaded and CSI is silent. WiROS's one-time setup
 * (`rmmod dhd; insmod <path>/dhd.ko; brctl addif br0 eth6`) and a configuration
 * (`wl -i eth6 chanspec CH/BW`, `wl -i eth6 monitor 1`, `nexutil -I eth6 -s500 -b -l34 -v …`)
 * make it report CSI. Not thread-safe. */
class RouterModel
{
public:
    using ScanProvider = std::function<std::vector<ScanEntry>(WifiBand band)>;

    explicit RouterModel(RouterTiming timing = {}, RouterKind kind = RouterKind::RtAc86u);
    RouterKind kind() const { return kind_; }

    /** Source of `wl scan` results (the emulator asks its simulator). */
    void setScanProvider(ScanProvider p) { scanProvider_ = std::move(p); }

    /** Runs one command: argv[0] is wl, nexutil, makecsiparams, insmod, rmmod, lsmod, brctl or
     * ifconfig. While rebooting every command fails with exit 255, as ssh would. */
    ToolResult execute(const Argv& argv, double now_s);

    /** Power cycle: forgets module, configuration and scan results; answers nothing for
     * RouterTiming::rebootDuration_s. */
    void reboot(double now_s);

    /** The state WiROS's setup leaves (module loaded, interface bridged and in monitor mode,
     * CSI on all cores and streams of `chanspec`), for trying the emulator without ssh. */
    void preconfigure(const Chanspec& chanspec, double now_s);

    bool rebooting(double now_s) const { return now_s < bootDoneAt_s_; }
    /** Interfaces whose CSI reaches the host at `now_s`. */
    std::vector<ActiveCapture> activeCaptures(double now_s) const;
    SilenceReason silenceReason(const WirelessInterface& itf, double now_s) const;
    /** The next time after `now_s` at which activeCaptures() changes without a command (end
     * of a retune, scan or boot); +inf if none is pending. */
    double nextTimedChange(double now_s) const;

    /** Incremented by every state change (command or reboot). */
    uint64_t generation() const { return generation_; }
    unsigned bootCount() const { return bootCount_; }
    DriverModule module() const { return module_; }
    const std::vector<WirelessInterface>& interfaces() const { return interfaces_; }
    const WirelessInterface* findInterface(const std::string& name) const;
    const RouterTiming& timing() const { return timing_; }
    void setTiming(const RouterTiming& t) { timing_ = t; }

    uint64_t commandsExecuted() const { return commandsExecuted_; }
    uint64_t commandsFailed() const { return commandsFailed_; }

    /** The router state as a JSON object (see share/emulator/README.md). */
    std::string toJson(double now_s) const;

private:
    ToolResult wl(const Argv& args, double now_s);
    ToolResult nexutil(const Argv& args, double now_s);
    ToolResult insmod(const Argv& args);
    ToolResult rmmod(const Argv& args);
    ToolResult lsmod(const Argv& args) const;
    ToolResult brctl(const Argv& args);
    ToolResult ifconfig(const Argv& args);
    ToolResult ip(const Argv& args);
    ToolResult iw(const Argv& args);
    /** The interface named `name`, or the one whose monitor interface it is (`*monitor`). */
    WirelessInterface* interfaceOrMonitor(const std::string& name, bool* monitor);
    ToolResult applyCsiParams(
        WirelessInterface& itf, const std::vector<uint8_t>& bytes, double now_s);
    void tune(WirelessInterface& itf, const Chanspec& cs, double now_s);
    WirelessInterface* mutableInterface(const std::string& name);
    void resetInterfaces(bool bridged);

    RouterTiming timing_;
    RouterKind kind_ = RouterKind::RtAc86u;
    ScanProvider scanProvider_;
    DriverModule module_ = DriverModule::Stock;
    std::vector<WirelessInterface> interfaces_;
    double bootDoneAt_s_ = -std::numeric_limits<double>::infinity();
    unsigned bootCount_ = 0;
    uint64_t generation_ = 0;
    uint64_t commandsExecuted_ = 0, commandsFailed_ = 0;
};

}  // namespace mrpt_wifi::emulator
