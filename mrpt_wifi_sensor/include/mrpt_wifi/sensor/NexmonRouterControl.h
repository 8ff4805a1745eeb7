/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiScan.h>
#include <mrpt_wifi/sensor/RouterShell.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** What the CSI extraction firmware should capture (makecsiparams arguments). */
struct CsiExtractionSettings
{
    Chanspec chanspec = Chanspec::make(155, 80, 2);  //!< 157/80 in Broadcom notation
    uint8_t coreMask = 0x0F;                         //!< -C: receive cores
    uint8_t streamMask = 0x0F;                       //!< -N: spatial streams
    /** -m: up to four transmitters. The hardware compares only the first two bytes of each;
     * the driver filters the rest in software. */
    std::vector<MacAddress> macFilter;
    uint16_t delay = 0;                      //!< -d (0: not passed)
    std::optional<uint8_t> firstPacketByte;  //!< -b: 802.11 frame type filter
};

/** Beacon injection for angle-of-departure measurements at other receivers. */
struct TransmitterSettings
{
    MacAddress source = MacAddress::fromString("02:4d:52:50:54:01");  //!< locally administered
    double rate_Hz = 50.0;
    unsigned streams = 1;
    unsigned count = 1000;  //!< bounded: the remote loop ends by itself
};

struct RouterSetupOptions
{
    std::string modulePath = "/jffs/dhd.ko";  //!< Nexmon-patched driver module
    std::string bridge = "br0";
    std::string interface5G = "eth6";
    std::string interface2G4 = "eth5";
    double commandTimeout_s = 10.0;
    double scanWait_s = 3.0;  //!< between `wl scan` and `wl scanresults`

    /** These values reach the router's shell: interface and bridge names must match
     *  `[A-Za-z0-9_.-]+`, the module path `[A-Za-z0-9_./+@%:,=-]+` (no whitespace, no shell
     *  metacharacters). Throws std::invalid_argument naming the .ini key (`setup_module_path`,
     *  `setup_bridge`, `setup_interface_5g`, `setup_interface_2g4`) and the value. */
    void validate() const;
};

/** `word` as one POSIX shell word: unchanged when it holds only `[A-Za-z0-9_./+@%:,=-]`,
 *  otherwise in single quotes (a `'` inside becomes `'\''`), as Python's shlex.quote. */
std::string shellQuote(const std::string& word);

/** Configures an RT-AC86U running Nexmon CSI through its shell, with the same commands WiROS
 * issues (DESIGN.md §4), batched so a reconfiguration costs one round trip. */
class NexmonRouterControl
{
public:
    /** Throws std::invalid_argument if `options` fail RouterSetupOptions::validate(). */
    NexmonRouterControl(std::shared_ptr<RouterShell> shell, RouterSetupOptions options);

    /** Once per router boot: reload the patched driver and bridge the 5 GHz interface (and
     *  the 2.4 GHz one with `bridge2G4`: a channel schedule that visits both bands), so the
     *  CSI datagrams reach the LAN. */
    void loadFirmwareModule(bool bridge2G4 = false);
    /** Stops CSI extraction on the radio of `cs`'s band (`makecsiparams -e 0`): a channel
     *  schedule leaving one band for the other, so only the visited channel is captured. */
    void stopCapture(const Chanspec& cs);
    std::string stopCaptureCommand(const Chanspec& cs) const;
    /** Tunes the radio and (re)starts CSI extraction. Throws RouterError. */
    void configure(const CsiExtractionSettings& s);
    /** Current chanspec of the interface of `band`, as the router reports it. */
    Chanspec currentChanspec(WifiBand band = WifiBand::Band5G);
    /** Scans for access points with `wl scan` / `wl scanresults`. */
    std::vector<ScannedAccessPoint> scan(WifiBand band = WifiBand::Band5G);
    /** Starts / stops beacon injection (transmitter mode). */
    void startTransmitter(const TransmitterSettings& t, WifiBand band = WifiBand::Band5G);
    void stopTransmitter();

    /** The command lines configure() would send (tests, logs). */
    std::string configureCommand(const CsiExtractionSettings& s) const;
    std::string interfaceFor(WifiBand band) const;
    RouterShell& shell() { return *shell_; }

private:
    std::shared_ptr<RouterShell> shell_;
    RouterSetupOptions options_;
};

/** Parses `wl scanresults` output (one block per BSS: SSID, RSSI, Channel, BSSID lines). */
std::vector<ScannedAccessPoint> parseWlScanResults(const std::string& text);
/** Scans with the host's own WiFi interface (`iw dev IFACE scan`, needs CAP_NET_ADMIN): no
 * interruption of the router's capture, as WiROS's host-side scan. Throws RouterError with
 * iw's message if it fails. */
std::vector<ScannedAccessPoint> scanWithHostInterface(const std::string& iface, double timeout_s);

/** Parses `iw dev IFACE scan` output (BSS, SSID, signal, DS Parameter set / primary channel,
 * VHT operation center segment). */
std::vector<ScannedAccessPoint> parseIwScan(const std::string& text);
/** An 802.11 beacon frame (as nexutil -s505 takes it) from `source` advertising `ssid`. */
std::vector<uint8_t> makeBeaconFrame(
    const MacAddress& source, const std::string& ssid, unsigned channel);

}  // namespace mrpt_wifi
