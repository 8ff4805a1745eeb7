/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt_wifi/sensor/AccessPointSelector.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>
#include <mrpt_wifi/sensor/LiveBearingWorker.h>
#include <mrpt_wifi/sensor/NexmonPiControl.h>
#include <mrpt_wifi/sensor/NexmonRouterControl.h>
#include <mrpt_wifi/sensor/UdpCsiReceiver.h>

#include <string>
#include <vector>

namespace mrpt_wifi
{
/** Everything a CWiFiCSISensor .ini section configures (share/rawlog-grabber/ documents every
 * key). Shared by the driver and csi-router, so both read the same files the same way. */
struct CsiSensorSettings
{
    enum class Source
    {
        Udp,
        Pcap,
        Live  //!< `interface:IFACE` or `serial:DEVICE` (CsiLiveSource)
    };
    Source source = Source::Udp;
    UdpCsiReceiverOptions udp;
    std::string pcapFile;
    double pcapSpeed = 1.0;
    std::string liveSource;        //!< the `source` value of a live source
    unsigned serialBaud = 921600;  //!< `serial_baud`
    std::string routerAddress;
    std::vector<MacPattern> macFilter;
    int minRssi_dBm = -128;
    CsiFrameAssemblerOptions assembler;
    double statusPeriod_s = 10.0;
    bool abortOnError = false;
    /** `record_chain_states`: measure each frame's inter-chain delays and jump states onto the
     *  observation (ChainStateRecorder), with state changes in the status line. */
    bool recordChainStates = true;

    bool routerControl = false;
    SshOptions ssh;
    RouterSetupOptions setup;
    bool loadModule = true;
    CsiExtractionSettings extraction;

    /** `pi_control`: Nexmon CSI on a Raspberry Pi's own chip, configured with the same
     *  `channel` / `packet_*` / mask keys, here (Local) or over ssh (`login_*` keys). */
    enum class PiControl
    {
        Off,
        Local,
        Ssh
    };
    PiControl piControl = PiControl::Off;
    PiSetupOptions pi;

    bool transmitterMode = false;
    TransmitterSettings transmitter;

    double scanPeriod_s = 0;
    bool scanWithHost = false;  //!< `scanner = host`: the host's `iw` instead of the router
    std::string scanInterface = "wlan0";
    bool autoChannel = false;
    bool autoMacFilter = true;
    AccessPointSelectorOptions selector;

    /** `channel_schedule`: channels visited in turn, `channel_dwell_s` each (empty: one
     *  channel). `scheduleFromScan` (`channel_schedule = scan`): the channels of the access
     *  points of the latest scan instead of a fixed list. */
    std::vector<Chanspec> channelSchedule;
    bool scheduleFromScan = false;
    double channelDwell_s = 2.0;
    bool hopping() const { return scheduleFromScan || !channelSchedule.empty(); }

    LiveBearingSettings bearing;  //!< `bearing_*`: bearings next to the capture (off: empty)

    /** Files named by the section (pcap_file, bearing_*) are resolved on loading
     *  (mrpt_wifi/obs/ConfigPaths.h); where one was found somewhere unexpected (the working
     *  directory, the data folder) a line for the log. */
    std::vector<std::string> pathNotes;
};

/** Reads a [section] of a rawlog-grabber .ini. Unknown keys and bad values throw
 * std::invalid_argument naming the section, the key (and the key a typo probably meant). */
CsiSensorSettings loadCsiSensorSettings(
    const mrpt::config::CConfigFileBase& config, const std::string& section,
    const std::string& sensorLabel);

}  // namespace mrpt_wifi
