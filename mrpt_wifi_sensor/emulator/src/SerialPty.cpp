/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <fcntl.h>
#include <mrpt/core/format.h>
#include <mrpt_wifi/emulator/SerialPty.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace mrpt_wifi::emulator
{
namespace fs = std::filesystem;

PtySerialPort::PtySerialPort(const std::string& linkPath)
{
    char name[256] = {0};
    if (::openpty(&master_, &slave_, name, nullptr, nullptr) != 0)
        throw std::runtime_error(std::string("openpty: ") + std::strerror(errno));
    slavePath_ = name;
    termios t{};
    ::tcgetattr(slave_, &t);
    ::cfmakeraw(&t);  // no echo, no line editing: the bytes as an ESP32's UART sends them
    ::tcsetattr(slave_, TCSANOW, &t);
    ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
    ::fcntl(master_, F_SETFD, FD_CLOEXEC);
    ::fcntl(slave_, F_SETFD, FD_CLOEXEC);
    if (!linkPath.empty())
    {
        std::error_code ec;
        if (fs::exists(fs::symlink_status(linkPath, ec)) && !fs::is_symlink(linkPath, ec))
        {
            ::close(master_), ::close(slave_);
            throw std::runtime_error(
                "serial link '" + linkPath + "' exists and is not a symbolic link");
        }
        fs::remove(linkPath, ec);
        fs::create_symlink(slavePath_, linkPath);
        linkPath_ = linkPath;
    }
}

PtySerialPort::~PtySerialPort()
{
    if (!linkPath_.empty())
    {
        std::error_code ec;
        fs::remove(linkPath_, ec);
    }
    if (master_ >= 0) ::close(master_);
    if (slave_ >= 0) ::close(slave_);
}

bool PtySerialPort::submit(std::string line)
{
    if (queuedBytes_ + line.size() > kMaxQueuedBytes)
    {
        ++linesDropped_;
        return false;
    }
    queuedBytes_ += line.size();
    queue_.push_back(std::move(line));
    return true;
}

void PtySerialPort::flush(const std::function<void(const std::string&)>& onWritten)
{
    while (!queue_.empty())
    {
        const std::string& line = queue_.front();
        const ssize_t n = ::write(master_, line.data() + offset_, line.size() - offset_);
        if (n <= 0) return;  // EAGAIN: the terminal's buffer is full, try again later
        offset_ += size_t(n);
        bytesWritten_ += uint64_t(n);
        if (offset_ < line.size()) return;
        ++linesWritten_;
        if (onWritten) onWritten(line);
        queuedBytes_ -= line.size();
        queue_.pop_front();
        offset_ = 0;
    }
}

size_t PtySerialPort::unreadBytes() const
{
    int n = 0;
    return ::ioctl(slave_, FIONREAD, &n) == 0 && n > 0 ? size_t(n) : 0;
}

std::string esp32CsiLine(
    const CObservationWiFiCSI& obs, uint32_t seq, uint64_t localTimestamp_us, int peak)
{
    if (obs.chanspec.bandwidthMHz != 20 || obs.nfft() != 64)
        throw std::invalid_argument(
            "an ESP32 reports 20 MHz L-LTF CSI; this frame is on " + obs.chanspec.asString());
    const auto* h = obs.pair(0, 0);
    float maxAbs = 0;
    for (unsigned i = 0; i < 64; ++i)
        maxAbs = std::max({maxAbs, std::abs(h[i].real()), std::abs(h[i].imag())});
    const float scale = maxAbs > 0 ? float(peak) / maxAbs : 0.0f;
    const auto int8Of = [scale](float x)
    { return int(std::clamp(std::lround(x * scale), -128L, 127L)); };
    // type,seq,mac,rssi,rate,sig_mode,mcs,cwb,smoothing,not_sounding,aggregation,stbc,
    // fec_coding,sgi,noise_floor,ampdu_cnt,channel,secondary_channel,local_timestamp,ant,
    // sig_len,rx_state,len,first_word_invalid
    const int noise =
        std::isfinite(obs.noiseFloor_dBm) ? int(std::lround(obs.noiseFloor_dBm)) : -92;
    std::string s = mrpt::format(
        "CSI_DATA,%u,%s,%d,11,0,0,0,0,1,0,0,0,0,%d,0,%u,0,%llu,0,100,0,128,0,\"[", seq,
        obs.transmitter.asString().c_str(), int(obs.rssi_dBm), noise, obs.chanspec.controlChannel(),
        static_cast<unsigned long long>(localTimestamp_us));
    // FFT order: buffer m is subcarrier k = m (m < 32) or m − 64: bin (m + 32) mod 64.
    for (unsigned m = 0; m < 64; ++m)
    {
        const auto v = h[(m + 32) & 63];
        s += (m ? " " : "") + std::to_string(int8Of(v.imag())) + " " +
             std::to_string(int8Of(v.real()));
    }
    return s + "]\"\n";
}

}  // namespace mrpt_wifi::emulator
