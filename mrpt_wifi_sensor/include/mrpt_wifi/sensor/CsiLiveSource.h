/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** A live CSI source CWiFiCSISensor polls besides its UDP socket and pcap replay:
 *  - `interface:IFACE`: libpcap live capture on a network interface of the Nexmon UDP
 *    datagrams the chip's firmware emits (the Raspberry Pi's wlan0, or `lo` to watch the
 *    emulator's loopback stream); the datagrams go to the frame assembler as from a socket;
 *  - `serial:DEVICE`: the `CSI_DATA` lines of an ESP32 running esp-csi on a serial port
 *    (raw mode, `baud`); every complete line becomes a frame. */
class CsiLiveSource
{
public:
    using DatagramSink = std::function<void(
        const uint8_t* data, size_t len, mrpt::Clock::time_point arrival,
        const std::string& source)>;
    using FrameSink = std::function<void(CObservationWiFiCSI::Ptr&&)>;

    /** What a source went through (for the sensor's status line). */
    struct Stats
    {
        uint64_t packets = 0;      //!< captured packets / lines read
        uint64_t delivered = 0;    //!< datagrams or frames handed on
        uint64_t rejected = 0;     //!< malformed lines (serial)
        uint64_t kernelDrops = 0;  //!< libpcap: dropped by the kernel
        std::string lastError;     //!< the latest rejected line's reason
    };

    virtual ~CsiLiveSource() = default;
    /** "interface wlan0 (udp dst port 5500)", "serial /dev/ttyUSB0 @ 921600". */
    virtual std::string describe() const = 0;
    /** Hands on everything that arrived, waiting at most `wait` for the first byte. */
    virtual void poll(
        const DatagramSink& onDatagram, const FrameSink& onFrame,
        std::chrono::milliseconds wait) = 0;
    virtual Stats stats() const = 0;
};

struct CsiLiveSourceOptions
{
    uint16_t udpPort = 5500;  //!< interface: destination port of the Nexmon datagrams
    unsigned baud = 921600;   //!< serial: esp-csi's default console rate
    std::string sensorLabel = "WIFI_CSI";
    mrpt::poses::CPose3D sensorPose;
};

/** True for a `source` value naming a live source (`interface:...`, `serial:...`). */
bool isLiveSourceSpec(const std::string& spec);
/** Opens the source a spec names. Throws std::runtime_error naming the interface / device
 * (missing, no permission, not a tty, unsupported baud rate). */
std::unique_ptr<CsiLiveSource> openLiveSource(
    const std::string& spec, const CsiLiveSourceOptions& options);

}  // namespace mrpt_wifi
