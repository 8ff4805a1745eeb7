/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/Clock.h>
#include <mrpt/system/md5.h>
#include <mrpt_wifi/sensor/RosMessages.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

namespace mrpt_wifi::ros1
{
namespace
{
// The field lists of the rf_msgs definitions (github ucsdwcsng/rf_msgs) and std_msgs/Header,
// without comments: what ROS 1 hashes, and what a bag carries for readers without the package.
const char* kHeaderDefinition =
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n";
const char* const kWifiFields =
    "std_msgs/Header header\n"
    "uint8 ap_id\n"
    "uint8[] txmac\n"
    "uint8 chan\n"
    "uint32 n_sub\n"
    "uint8 n_rows\n"
    "uint8 n_cols\n"
    "uint8 bw\n"
    "uint8 mcs\n"
    "int32 rssi\n"
    "uint32 fc\n"
    "uint32 seq_num\n"
    "float64[] csi_real\n"
    "float64[] csi_imag\n"
    "string rx_id\n"
    "uint32 msg_id\n";
const char* const kBearingFields =
    "std_msgs/Header header\n"
    "uint8 ap_id\n"
    "uint8[] txmac\n"
    "uint8 n_tx\n"
    "uint8 n_rx\n"
    "uint32 seq\n"
    "int32[] rssi\n"
    "float64[] aoa\n";

std::string withHeaderDependency(const std::string& fields)
{
    return fields +
           "\n================================================================================\n"
           "MSG: std_msgs/Header\n" +
           kHeaderDefinition;
}

MessageType makeType(const std::string& name, const char* fields)
{
    const std::string headerMd5 = messageMd5(kHeaderDefinition, {});
    return {
        name, messageMd5(fields, {{"std_msgs/Header", headerMd5}}), withHeaderDependency(fields)};
}

// ---- wire format
class Writer
{
public:
    template <typename T>
    void put(T v)
    {
        static_assert(std::is_arithmetic_v<T>);
        const size_t at = bytes_.size();
        bytes_.resize(at + sizeof(T));
        std::memcpy(bytes_.data() + at, &v, sizeof(T));  // x86/ARM: little-endian as ROS
    }
    template <typename T>
    void putArray(const std::vector<T>& v)
    {
        put(uint32_t(v.size()));
        for (const T& x : v) put(x);
    }
    void putString(const std::string& s)
    {
        put(uint32_t(s.size()));
        bytes_.insert(bytes_.end(), s.begin(), s.end());
    }
    void putHeader(const Header& h)
    {
        put(h.seq), put(h.stampSec), put(h.stampNsec), putString(h.frameId);
    }
    std::vector<uint8_t> take() { return std::move(bytes_); }

private:
    std::vector<uint8_t> bytes_;
};

class Reader
{
public:
    Reader(const uint8_t* d, size_t n) : d_(d), n_(n) {}
    template <typename T>
    bool get(T& v, const char* what)
    {
        if (n_ - pos_ < sizeof(T)) return fail(what, sizeof(T));
        std::memcpy(&v, d_ + pos_, sizeof(T));
        pos_ += sizeof(T);
        return true;
    }
    template <typename T>
    bool getArray(std::vector<T>& v, const char* what)
    {
        uint32_t count = 0;
        if (!get(count, what)) return false;
        if ((n_ - pos_) / sizeof(T) < count) return fail(what, size_t(count) * sizeof(T));
        v.resize(count);
        if (count) std::memcpy(v.data(), d_ + pos_, size_t(count) * sizeof(T));
        pos_ += size_t(count) * sizeof(T);
        return true;
    }
    bool getString(std::string& s, const char* what)
    {
        std::vector<uint8_t> b;
        if (!getArray(b, what)) return false;
        s.assign(b.begin(), b.end());
        return true;
    }
    bool getHeader(Header& h)
    {
        return get(h.seq, "header.seq") && get(h.stampSec, "header.stamp") &&
               get(h.stampNsec, "header.stamp") && getString(h.frameId, "header.frame_id");
    }
    bool done()
    {
        if (pos_ == n_) return true;
        why_ = std::to_string(n_ - pos_) + " bytes left over after the last field";
        return false;
    }
    const std::string& why() const { return why_; }

private:
    bool fail(const char* what, size_t need)
    {
        why_ = std::string(what) + " needs " + std::to_string(need) + " bytes at " +
               std::to_string(pos_) + ", the message has " + std::to_string(n_ - pos_) + " left";
        return false;
    }
    const uint8_t* d_;
    size_t n_, pos_ = 0;
    std::string why_;
};

Header headerAt(mrpt::Clock::time_point t)
{
    Header h;
    const double s = std::max(0.0, mrpt::Clock::toDouble(t));
    h.stampSec = uint32_t(std::floor(s));
    h.stampNsec = uint32_t(std::llround((s - std::floor(s)) * 1e9));
    if (h.stampNsec >= 1000000000u) h.stampSec++, h.stampNsec -= 1000000000u;
    return h;
}

std::vector<uint8_t> macBytes(const MacAddress& m)
{
    return std::vector<uint8_t>(m.bytes.begin(), m.bytes.end());
}
}  // namespace

std::string messageMd5(
    const std::string& definition, const std::vector<std::pair<std::string, std::string>>& nested)
{
    // ROS 1 (genmsg): constants first, then fields as "type name", comments and blank lines
    // dropped, whitespace normalised, each nested message type replaced by its MD5.
    std::istringstream in(definition);
    std::string line, text;
    for (std::string raw; std::getline(in, raw);)
    {
        if (const auto hash = raw.find('#'); hash != std::string::npos) raw.erase(hash);
        std::istringstream words(raw);
        std::string type, name;
        if (!(words >> type >> name)) continue;
        for (const auto& [t, md5] : nested)
            if (type == t) type = md5;
        text += (text.empty() ? "" : "\n") + type + " " + name;
    }
    return mrpt::system::md5(text);
}

const char* wifiFieldLines()
{
    return kWifiFields;
}
const char* bearingFieldLines()
{
    return kBearingFields;
}

const MessageType& wifiType()
{
    static const MessageType t = makeType("rf_msgs/Wifi", kWifiFields);
    return t;
}

const MessageType& bearingType()
{
    static const MessageType t = makeType("rf_msgs/Bearing", kBearingFields);
    return t;
}

std::vector<uint8_t> serialize(const WifiMessage& m)
{
    Writer w;
    w.putHeader(m.header);
    w.put(m.apId), w.putArray(m.txmac), w.put(m.chan), w.put(m.nSub), w.put(m.nRows);
    w.put(m.nCols), w.put(m.bw), w.put(m.mcs), w.put(m.rssi), w.put(m.fc), w.put(m.seqNum);
    w.putArray(m.csiReal), w.putArray(m.csiImag), w.putString(m.rxId), w.put(m.msgId);
    return w.take();
}

std::vector<uint8_t> serialize(const BearingMessage& m)
{
    Writer w;
    w.putHeader(m.header);
    w.put(m.apId), w.putArray(m.txmac), w.put(m.nTx), w.put(m.nRx), w.put(m.seq);
    w.putArray(m.rssi), w.putArray(m.aoa);
    return w.take();
}

bool deserialize(const uint8_t* data, size_t len, WifiMessage& m, std::string& why)
{
    Reader r(data, len);
    const bool ok = r.getHeader(m.header) && r.get(m.apId, "ap_id") &&
                    r.getArray(m.txmac, "txmac") && r.get(m.chan, "chan") &&
                    r.get(m.nSub, "n_sub") && r.get(m.nRows, "n_rows") &&
                    r.get(m.nCols, "n_cols") && r.get(m.bw, "bw") && r.get(m.mcs, "mcs") &&
                    r.get(m.rssi, "rssi") && r.get(m.fc, "fc") && r.get(m.seqNum, "seq_num") &&
                    r.getArray(m.csiReal, "csi_real") && r.getArray(m.csiImag, "csi_imag") &&
                    r.getString(m.rxId, "rx_id") && r.get(m.msgId, "msg_id") && r.done();
    if (!ok) why = r.why();
    return ok;
}

bool deserialize(const uint8_t* data, size_t len, BearingMessage& m, std::string& why)
{
    Reader r(data, len);
    const bool ok = r.getHeader(m.header) && r.get(m.apId, "ap_id") &&
                    r.getArray(m.txmac, "txmac") && r.get(m.nTx, "n_tx") && r.get(m.nRx, "n_rx") &&
                    r.get(m.seq, "seq") && r.getArray(m.rssi, "rssi") && r.getArray(m.aoa, "aoa") &&
                    r.done();
    if (!ok) why = r.why();
    return ok;
}

bool toObservation(const WifiMessage& m, CObservationWiFiCSI& obs, std::string& why)
{
    const size_t n = size_t(m.nSub) * m.nRows * m.nCols;
    if (m.csiReal.size() != n || m.csiImag.size() != n)
    {
        why = "csi_real/csi_imag hold " + std::to_string(m.csiReal.size()) + "/" +
              std::to_string(m.csiImag.size()) +
              " values, n_sub·n_rows·n_cols = " + std::to_string(m.nSub) + "·" +
              std::to_string(m.nRows) + "·" + std::to_string(m.nCols) + " = " + std::to_string(n);
        return false;
    }
    if (m.nRows < 1 || m.nCols < 1 || m.nRows > CObservationWiFiCSI::kMaxChains ||
        m.nCols > CObservationWiFiCSI::kMaxChains)
    {
        why = "n_rows " + std::to_string(m.nRows) + ", n_cols " + std::to_string(m.nCols) +
              " (1–8 each)";
        return false;
    }
    Chanspec cs;
    try
    {
        // WiROS fills chan from the chanspec; the centre and control channels of 40/80 MHz
        // blocks never coincide, so either is understood.
        cs = Chanspec::fromString(std::to_string(m.chan) + "/" + std::to_string(m.bw));
    }
    catch (const std::exception&)
    {
        why = "channel " + std::to_string(m.chan) + " at " + std::to_string(m.bw) +
              " MHz does not exist";
        return false;
    }
    if (m.nSub != cs.nfft())
    {
        why = "n_sub " + std::to_string(m.nSub) + " is not the FFT size of " +
              std::to_string(m.bw) + " MHz (" + std::to_string(cs.nfft()) + ")";
        return false;
    }
    if (m.txmac.size() != 6)
    {
        why = "txmac has " + std::to_string(m.txmac.size()) + " bytes (6)";
        return false;
    }
    obs.chanspec = cs;
    obs.source = "wiros";
    std::copy(m.txmac.begin(), m.txmac.end(), obs.transmitter.bytes.begin());
    obs.rssi_dBm = int8_t(std::clamp(m.rssi, -128, 127));
    obs.sequenceNumber = uint16_t((m.seqNum >> 4) & 0x0FFF);
    obs.fragmentNumber = uint8_t(m.seqNum & 0x0F);
    obs.frameControl = uint8_t(m.fc & 0xFF);
    obs.firmwareCounter = uint16_t(m.msgId & 0xFFFF);
    obs.routerAddress = m.rxId;
    obs.timestamp = mrpt::Clock::fromDouble(double(m.header.stampSec) + 1e-9 * m.header.stampNsec);
    obs.resize(m.nCols, m.nRows, m.nSub);
    for (unsigned tx = 0; tx < m.nCols; ++tx)
        for (unsigned rx = 0; rx < m.nRows; ++rx)
        {
            bool any = false;
            for (unsigned k = 0; k < m.nSub; ++k)
            {
                const size_t i = k + size_t(m.nSub) * (rx + size_t(m.nRows) * tx);
                obs.at(tx, rx, k) = {float(m.csiReal[i]), float(m.csiImag[i])};
                any |= m.csiReal[i] != 0 || m.csiImag[i] != 0;
            }
            obs.setPresent(tx, rx, any);
        }
    return true;
}

WifiMessage fromObservation(const CObservationWiFiCSI& obs, const std::string& rxId)
{
    WifiMessage m;
    m.header = headerAt(obs.timestamp);
    m.txmac = macBytes(obs.transmitter);
    m.chan = obs.chanspec.centerChannel;
    m.nSub = obs.nfft();
    m.nRows = obs.nRx, m.nCols = obs.nTx;
    m.bw = uint8_t(obs.chanspec.bandwidthMHz);
    m.rssi = obs.rssi_dBm;
    m.fc = obs.frameControl;
    m.seqNum = uint32_t(obs.sequenceNumber) << 4 | (obs.fragmentNumber & 0x0F);
    const size_t n = size_t(m.nSub) * m.nRows * m.nCols;
    m.csiReal.assign(n, 0.0), m.csiImag.assign(n, 0.0);
    for (unsigned tx = 0; tx < obs.nTx; ++tx)
        for (unsigned rx = 0; rx < obs.nRx; ++rx)
        {
            if (!obs.isPresent(tx, rx)) continue;  // zeros, as WiROS leaves a missing pair
            for (unsigned k = 0; k < m.nSub; ++k)
            {
                const size_t i = k + size_t(m.nSub) * (rx + size_t(m.nRows) * tx);
                m.csiReal[i] = obs.at(tx, rx, k).real();
                m.csiImag[i] = obs.at(tx, rx, k).imag();
            }
        }
    m.rxId = rxId;
    return m;
}

BearingMessage fromBearing(const CObservationWiFiBearing& b)
{
    BearingMessage m;
    m.header = headerAt(b.timestamp);
    m.txmac = macBytes(b.transmitter);
    m.nRx = 0, m.nTx = 0;  // the bearing does not carry the array sizes
    m.rssi = {int32_t(b.rssi_dBm)};
    m.aoa = {b.aoa_rad};
    return m;
}

}  // namespace mrpt_wifi::ros1
