/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt_wifi/sensor/UdpCsiReceiver.h>

#include <memory>
#include <optional>
#include <string>

namespace mrpt_wifi
{
/** Wheel odometry received as small text datagrams over UDP (loopback), sent by the robot's
 *  own software (Debian's MRPT has no robot-base driver; share/odometry/send_odometry.py is an
 *  example sender) or by `rt-ac86u-emulator --odometry-port N`: one CObservationOdometry per
 *  datagram, stamped with its kernel arrival time (like the CSI), for rawlog-grabber and
 *  wifi-localize.
 *
 *  Datagram (ASCII, one line): `MRPT_WIFI_ODO 1 SEQ T X Y PHI VX VY OMEGA`
 *  (share/odometry/README.md). Malformed datagrams are counted and reported, never turned into
 *  observations; gaps in SEQ are counted as lost.
 *
 *  .ini keys (besides CGenericSensor's sensorLabel, process_rate, ...):
 *    udp_port          = 5600        ; required
 *    udp_bind_address  = 127.0.0.1   ; an address of this machine
 *
 *  Registered as `driver = CWiFiOdometryUdpSensor` by libmrpt_wifi_sensor.so. */
class CWiFiOdometryUdpSensor : public mrpt::hwdrivers::CGenericSensor
{
    DEFINE_GENERIC_SENSOR(CWiFiOdometryUdpSensor)

public:
    CWiFiOdometryUdpSensor();
    ~CWiFiOdometryUdpSensor() override;

    void initialize() override;
    void doProcess() override;

    /** Parses one datagram into `out` (odometry, velocities); false if it isn't one. */
    static bool parseDatagram(
        const uint8_t* data, size_t len, mrpt::obs::CObservationOdometry& out, uint64_t& seq);

    uint64_t received() const { return received_; }
    uint64_t malformed() const { return malformed_; }
    uint64_t lost() const { return lost_; }
    uint16_t boundPort() const { return receiver_ ? receiver_->boundPort() : 0; }

protected:
    void loadConfig_sensorSpecific(
        const mrpt::config::CConfigFileBase& config, const std::string& section) override;

private:
    UdpCsiReceiverOptions options_;
    std::unique_ptr<UdpCsiReceiver> receiver_;
    std::optional<uint64_t> lastSeq_;
    uint64_t received_ = 0, malformed_ = 0, lost_ = 0;
};

}  // namespace mrpt_wifi
