/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <fcntl.h>
#include <mrpt_wifi/sensor/CsiLiveSource.h>
#include <mrpt_wifi/sensor/Esp32CsiFormat.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <pcap/pcap.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
constexpr std::string_view kInterfacePrefix = "interface:", kSerialPrefix = "serial:";
constexpr size_t kMaxLineBytes = 16384;  //!< longer "lines" are noise, not esp-csi output

/** libpcap live capture of the Nexmon datagrams on an interface. */
class PcapLiveSource : public CsiLiveSource
{
public:
    PcapLiveSource(const std::string& iface, const CsiLiveSourceOptions& o)
        : iface_(iface), port_(o.udpPort)
    {
        char err[PCAP_ERRBUF_SIZE] = {0};
        handle_ = pcap_create(iface.c_str(), err);
        if (!handle_)
            throw std::runtime_error("cannot capture on interface '" + iface + "': " + err);
        pcap_set_snaplen(handle_, 65535);
        pcap_set_promisc(handle_, 0);
        pcap_set_timeout(handle_, 10);
        pcap_set_immediate_mode(handle_, 1);
        if (pcap_activate(handle_) < 0)
            fail("cannot capture on interface '" + iface + "': " + pcap_geterr(handle_));
        const std::string filter = "udp dst port " + std::to_string(port_);
        bpf_program prog{};
        if (pcap_compile(handle_, &prog, filter.c_str(), 1, PCAP_NETMASK_UNKNOWN) < 0 ||
            pcap_setfilter(handle_, &prog) < 0)
        {
            pcap_freecode(&prog);
            fail("interface '" + iface + "': filter '" + filter + "': " + pcap_geterr(handle_));
        }
        pcap_freecode(&prog);
        if (pcap_setnonblock(handle_, 1, err) < 0)
            fail("interface '" + iface + "': " + std::string(err));
        linkType_ = pcap_datalink(handle_);
    }
    ~PcapLiveSource() override
    {
        if (handle_) pcap_close(handle_);
    }
    std::string describe() const override
    {
        return "interface " + iface_ + " (udp dst port " + std::to_string(port_) + ")";
    }
    void poll(
        const DatagramSink& onDatagram, const FrameSink&, std::chrono::milliseconds wait) override
    {
        const int fd = pcap_get_selectable_fd(handle_);
        if (fd >= 0 && wait.count() > 0)
        {
            pollfd p{fd, POLLIN, 0};
            ::poll(&p, 1, int(wait.count()));
        }
        for (int budget = 10000; budget > 0; --budget)
        {
            pcap_pkthdr* hdr = nullptr;
            const u_char* pkt = nullptr;
            const int rc = pcap_next_ex(handle_, &hdr, &pkt);
            if (rc != 1) break;  // 0: nothing more now; errors are reported by stats()
            ++stats_.packets;
            PcapUdpDatagram d;
            if (!extractUdpDatagram(linkType_, pkt, hdr->caplen, port_, d, pcapStats_)) continue;
            ++stats_.delivered;
            onDatagram(d.payload, d.payloadLength, mrpt::Clock::now(), d.sourceAddress);
        }
    }
    Stats stats() const override
    {
        Stats s = stats_;
        pcap_stat ps{};
        if (pcap_stats(handle_, &ps) == 0) s.kernelDrops = ps.ps_drop;
        return s;
    }

private:
    [[noreturn]] void fail(const std::string& what)
    {
        pcap_close(handle_);
        handle_ = nullptr;
        throw std::runtime_error(what);
    }
    std::string iface_;
    uint16_t port_;
    pcap_t* handle_ = nullptr;
    int linkType_ = 0;
    PcapReader::Stats pcapStats_;
    Stats stats_;
};

speed_t baudConstant(unsigned baud)
{
    static const std::map<unsigned, speed_t> rates = {
        {9600, B9600},      {19200, B19200},     {38400, B38400},     {57600, B57600},
        {115200, B115200},  {230400, B230400},   {460800, B460800},   {500000, B500000},
        {921600, B921600},  {1000000, B1000000}, {1500000, B1500000}, {2000000, B2000000},
        {3000000, B3000000}};
    const auto it = rates.find(baud);
    if (it == rates.end())
        throw std::runtime_error(
            "serial baud rate " + std::to_string(baud) +
            " not supported (9600 .. 3000000, the standard rates)");
    return it->second;
}

/** esp-csi CSI_DATA lines on a serial port. */
class SerialEsp32Source : public CsiLiveSource
{
public:
    SerialEsp32Source(const std::string& device, const CsiLiveSourceOptions& o)
        : device_(device), options_(o)
    {
        const speed_t speed = baudConstant(o.baud);
        fd_ = ::open(device.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
        if (fd_ < 0)
            throw std::runtime_error(
                "cannot open serial port '" + device + "': " + std::strerror(errno));
        termios t{};
        if (tcgetattr(fd_, &t) != 0)
        {
            const std::string why = std::strerror(errno);
            ::close(fd_);
            throw std::runtime_error("'" + device + "' is not a serial port: " + why);
        }
        cfmakeraw(&t);
        cfsetispeed(&t, speed);
        cfsetospeed(&t, speed);
        t.c_cflag |= CLOCAL | CREAD;
        tcsetattr(fd_, TCSANOW, &t);
    }
    ~SerialEsp32Source() override
    {
        if (fd_ >= 0) ::close(fd_);
    }
    std::string describe() const override
    {
        return "serial " + device_ + " @ " + std::to_string(options_.baud) + " baud (ESP32)";
    }
    void poll(
        const DatagramSink&, const FrameSink& onFrame, std::chrono::milliseconds wait) override
    {
        if (wait.count() > 0)
        {
            pollfd p{fd_, POLLIN, 0};
            ::poll(&p, 1, int(wait.count()));
        }
        char buf[4096];
        for (;;)
        {
            const ssize_t n = ::read(fd_, buf, sizeof(buf));
            if (n <= 0) break;  // EAGAIN: nothing more now; EIO: the other end is gone
            pending_.append(buf, size_t(n));
            size_t start = 0;
            for (size_t eol; (eol = pending_.find('\n', start)) != std::string::npos;
                 start = eol + 1)
                handleLine(std::string_view(pending_).substr(start, eol - start), onFrame);
            pending_.erase(0, start);
            if (pending_.size() > kMaxLineBytes) pending_.clear();
        }
    }
    Stats stats() const override { return stats_; }

private:
    void handleLine(std::string_view line, const FrameSink& onFrame)
    {
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (!esp32::isCsiLine(line)) return;  // boot messages, logs
        ++stats_.packets;
        esp32::Esp32Line l;
        std::string why;
        auto obs = CObservationWiFiCSI::Create();
        if (!esp32::parseLine(line, l, why) || !esp32::toObservation(l, *obs, why))
        {
            ++stats_.rejected;
            stats_.lastError = why;
            return;
        }
        obs->timestamp = mrpt::Clock::now();
        obs->sensorLabel = options_.sensorLabel;
        obs->sensorPose = options_.sensorPose;
        obs->routerAddress = device_;
        ++stats_.delivered;
        onFrame(std::move(obs));
    }
    std::string device_;
    CsiLiveSourceOptions options_;
    int fd_ = -1;
    std::string pending_;
    Stats stats_;
};
}  // namespace

bool isLiveSourceSpec(const std::string& spec)
{
    return spec.rfind(kInterfacePrefix, 0) == 0 || spec.rfind(kSerialPrefix, 0) == 0;
}

std::unique_ptr<CsiLiveSource> openLiveSource(
    const std::string& spec, const CsiLiveSourceOptions& options)
{
    if (spec.rfind(kInterfacePrefix, 0) == 0 && spec.size() > kInterfacePrefix.size())
        return std::make_unique<PcapLiveSource>(spec.substr(kInterfacePrefix.size()), options);
    if (spec.rfind(kSerialPrefix, 0) == 0 && spec.size() > kSerialPrefix.size())
        return std::make_unique<SerialEsp32Source>(spec.substr(kSerialPrefix.size()), options);
    throw std::runtime_error(
        "live source '" + spec + "' (expected interface:IFACE or serial:DEVICE)");
}

}  // namespace mrpt_wifi
