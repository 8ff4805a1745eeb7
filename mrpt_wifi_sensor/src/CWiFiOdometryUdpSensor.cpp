/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt_wifi/obs/ConfigKeys.h>
#include <mrpt_wifi/sensor/CWiFiOdometryUdpSensor.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <stdexcept>

using namespace mrpt_wifi;

IMPLEMENTS_GENERIC_SENSOR(CWiFiOdometryUdpSensor, mrpt_wifi)

CWiFiOdometryUdpSensor::CWiFiOdometryUdpSensor()
{
    m_sensorLabel = "ODOMETRY";
    options_.bindAddress = "127.0.0.1";
    options_.port = 0;
    options_.receiveBufferBytes = 1 << 20;
}

CWiFiOdometryUdpSensor::~CWiFiOdometryUdpSensor() = default;

void CWiFiOdometryUdpSensor::loadConfig_sensorSpecific(
    const mrpt::config::CConfigFileBase& c, const std::string& section)
{
    mrpt_wifi::config::requireKnownKeys(
        c, section, mrpt_wifi::config::sectionKeys("CWiFiOdometryUdpSensor"));
    const int port = c.read_int(section, "udp_port", -1, true);
    if (port < 0 || port > 65535)
        throw std::invalid_argument(
            "section '" + section + "', udp_port = " + std::to_string(port) +
            ": must be in 0..65535");
    options_.port = uint16_t(port);
    options_.bindAddress = c.read_string(section, "udp_bind_address", options_.bindAddress);
}

void CWiFiOdometryUdpSensor::initialize()
{
    receiver_ = std::make_unique<UdpCsiReceiver>(options_);  // throws naming address and port
    m_state = ssWorking;
}

bool CWiFiOdometryUdpSensor::parseDatagram(
    const uint8_t* data, size_t len, mrpt::obs::CObservationOdometry& out, uint64_t& seq)
{
    if (len == 0 || len > 512) return false;
    const std::string text(reinterpret_cast<const char*>(data), len);
    unsigned version = 0;
    unsigned long long s = 0;
    double t = 0, x = 0, y = 0, phi = 0, vx = 0, vy = 0, w = 0;
    int used = 0;
    if (std::sscanf(
            text.c_str(), "MRPT_WIFI_ODO %u %llu %lf %lf %lf %lf %lf %lf %lf%n", &version, &s, &t,
            &x, &y, &phi, &vx, &vy, &w, &used) != 9 ||
        version != 1)
        return false;
    for (size_t i = size_t(used); i < text.size(); ++i)
        if (!std::isspace(static_cast<unsigned char>(text[i]))) return false;
    for (double v : {t, x, y, phi, vx, vy, w})
        if (!std::isfinite(v)) return false;
    seq = s;
    out.odometry = mrpt::poses::CPose2D(x, y, phi);
    out.hasVelocities = true;
    out.velocityLocal = mrpt::math::TTwist2D(vx, vy, w);
    out.hasEncodersInfo = false;
    return true;
}

void CWiFiOdometryUdpSensor::doProcess()
{
    if (!receiver_) return;
    receiver_->receive(
        [this](const uint8_t* data, size_t len, mrpt::Clock::time_point arrival, const std::string&)
        {
            auto obs = mrpt::obs::CObservationOdometry::Create();
            uint64_t seq = 0;
            if (!parseDatagram(data, len, *obs, seq))
            {
                if (malformed_++ == 0)
                    std::cerr << "[CWiFiOdometryUdpSensor:" << m_sensorLabel
                              << "] a datagram that is not MRPT_WIFI_ODO 1 was ignored (counted)\n";
                return;
            }
            if (lastSeq_ && seq > *lastSeq_ + 1) lost_ += seq - *lastSeq_ - 1;
            lastSeq_ = seq;
            ++received_;
            obs->timestamp = arrival;
            obs->sensorLabel = m_sensorLabel;
            appendObservation(obs);
        },
        std::chrono::milliseconds(0), 10000);
}
