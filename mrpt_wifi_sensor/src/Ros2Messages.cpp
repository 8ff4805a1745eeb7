/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>
#include <mrpt_wifi/sensor/Ros2Messages.h>

#include <map>
#include <set>
#include <sstream>

namespace mrpt_wifi::ros2
{
namespace
{
// rf_msgs (github ucsdwcsng/rf_msgs): its ROS 2 package has the ROS 1 fields. Nested types
// are spelled as their "MSG:" blocks name them (pkg/msg/Type): rosbag2 copies the .msg text
// ("std_msgs/Header"), which readers such as @foxglove/rosmsg do not match to
// "MSG: std_msgs/msg/Header".
std::string ros2FieldLines(const std::string& ros1Lines)
{
    const std::string ros1Header = "std_msgs/Header ", ros2Header = "std_msgs/msg/Header ";
    std::string lines = ros1Lines;
    for (size_t at = lines.find(ros1Header); at != std::string::npos;
         at = lines.find(ros1Header, at + ros2Header.size()))
        lines.replace(at, ros1Header.size(), ros2Header);
    return lines;
}

const char* kSeparator =
    "================================================================================\n";

std::string withDependencies(const std::string& fields)
{
    return fields + kSeparator +
           "MSG: std_msgs/msg/Header\n"
           "builtin_interfaces/msg/Time stamp\n"
           "string frame_id\n" +
           kSeparator +
           "MSG: builtin_interfaces/msg/Time\n"
           "int32 sec\n"
           "uint32 nanosec\n";
}

// ---- definition comparison
using FieldList = std::vector<std::pair<std::string, std::string>>;  // (type, name)

bool isPrimitive(const std::string& t)
{
    static const std::set<std::string> kPrimitive = {
        "bool",   "byte",  "char",   "float32", "float64", "int8",   "uint8",  "int16",
        "uint16", "int32", "uint32", "int64",   "uint64",  "string", "wstring"};
    return kPrimitive.count(t) > 0;
}

// "pkg/msg/T" and "pkg/T" alike as "pkg/T"; a bare "Header" is std_msgs's; another bare
// non-primitive name belongs to the package of the definition it appears in.
std::string canonicalType(const std::string& type, const std::string& package)
{
    std::string base = type, suffix;
    if (const auto bracket = base.find('['); bracket != std::string::npos)
        suffix = base.substr(bracket), base.erase(bracket);
    std::string bound;
    if (const auto le = base.find("<="); le != std::string::npos)
        bound = base.substr(le), base.erase(le);
    if (isPrimitive(base)) return base + bound + suffix;
    if (const auto msg = base.find("/msg/"); msg != std::string::npos) base.erase(msg, 4);
    if (base.find('/') == std::string::npos)
        base = (base == "Header" ? "std_msgs" : package) + "/" + base;
    return base + bound + suffix;
}

std::string packageOf(const std::string& canonicalName)
{
    return canonicalName.substr(0, canonicalName.find('/'));
}

// Splits schema text into its types' field lists: the first block under `mainType`, the
// others under their "MSG:" names, all canonical.
std::map<std::string, FieldList> parseDefinition(
    const std::string& text, const std::string& mainType)
{
    std::map<std::string, FieldList> types;
    std::string current = canonicalType(mainType, "");
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
    {
        if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
        std::istringstream words(line);
        std::string type, name;
        if (!(words >> type)) continue;
        if (type.find_first_not_of('=') == std::string::npos) continue;  // block separator
        if (type == "MSG:" || type == "IDL:")
        {
            std::string dependency;
            words >> dependency;
            current = canonicalType(dependency, "");
            types[current];  // an empty block still declares the type
            continue;
        }
        if (!(words >> name)) continue;
        if (name.find('=') != std::string::npos) continue;  // constant "int32 X=1"
        std::string next;
        if (words >> next && next[0] == '=') continue;  // constant "int32 X = 1"
        types[current].emplace_back(canonicalType(type, packageOf(current)), name);
    }
    return types;
}

bool compareType(
    const std::string& typeName, const std::map<std::string, FieldList>& expected,
    const std::map<std::string, FieldList>& given, std::string& why)
{
    const auto want = expected.find(typeName);
    const auto have = given.find(typeName);
    if (want == expected.end()) return true;  // not one of ours to check
    if (have == given.end())
    {
        why = "the definition of " + typeName + " is missing";
        return false;
    }
    const FieldList &a = want->second, &b = have->second;
    for (size_t i = 0; i < std::max(a.size(), b.size()); ++i)
    {
        if (i >= b.size())
        {
            why = typeName + ": field '" + a[i].second + "' (" + a[i].first + ") is missing";
            return false;
        }
        if (i >= a.size())
        {
            why = typeName + ": unexpected field '" + b[i].second + "' (" + b[i].first + ")";
            return false;
        }
        if (a[i] != b[i])
        {
            why = typeName + ": field " + std::to_string(i + 1) + " is '" + b[i].first + " " +
                  b[i].second + "', expected '" + a[i].first + " " + a[i].second + "'";
            return false;
        }
        std::string base = a[i].first.substr(0, a[i].first.find('['));
        if (!isPrimitive(base) && !compareType(base, expected, given, why)) return false;
    }
    return true;
}

// ---- CDR
class CdrWriter
{
public:
    /** `bound`: at least the message's size. fastcdr leaves alignment padding unwritten, so it
     *  writes into zeroed memory of this size (its own growing buffer would leave whatever the
     *  allocator had there, and the same message would not give the same bytes). */
    explicit CdrWriter(size_t bound)
        : bytes_(bound, 0),
          buffer_(reinterpret_cast<char*>(bytes_.data()), bytes_.size()),
          cdr_(buffer_, eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS, eprosima::fastcdr::Cdr::DDS_CDR)
    {
        cdr_.serialize_encapsulation();  // 00 01 00 00
    }
    template <typename T>
    CdrWriter& operator<<(const T& v)
    {
        cdr_ << v;
        return *this;
    }
    void putHeader(const ros1::Header& h)
    {
        cdr_ << int32_t(h.stampSec) << h.stampNsec << h.frameId;
    }
    std::vector<uint8_t> take()
    {
        bytes_.resize(cdr_.getSerializedDataLength());
        return std::move(bytes_);
    }

private:
    std::vector<uint8_t> bytes_;
    eprosima::fastcdr::FastBuffer buffer_;
    eprosima::fastcdr::Cdr cdr_;
};

// Fixed fields, counts, NULs and up to 7 bytes of alignment before each of ~20 fields.
constexpr size_t kCdrOverhead = 256;

// Reads fields in order, remembering which one failed and where.
class CdrReader
{
public:
    CdrReader(const uint8_t* data, size_t len)
        : buffer_(reinterpret_cast<char*>(const_cast<uint8_t*>(data)), len),
          cdr_(buffer_, eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS, eprosima::fastcdr::Cdr::DDS_CDR),
          data_(data),
          len_(len)
    {
    }
    bool encapsulation()
    {
        // Plain CDR only (00 00 big-, 00 01 little-endian); XCDR2 and parameter lists are
        // another layout.
        if (len_ < 4 || data_[0] != 0 || data_[1] > 1)
        {
            why_ = len_ < 4 ? "the message has " + std::to_string(len_) +
                                  " bytes, shorter than the CDR encapsulation header"
                            : "encapsulation " + hex(data_[0]) + " " + hex(data_[1]) +
                                  " is not plain CDR (00 00 or 00 01)";
            return false;
        }
        return read("encapsulation", [&] { cdr_.read_encapsulation(); });
    }
    template <typename T>
    bool get(T& v, const char* what)
    {
        return read(what, [&] { cdr_ >> v; });
    }
    bool getHeader(ros1::Header& h)
    {
        int32_t sec = 0;
        if (!get(sec, "header.stamp.sec") || !get(h.stampNsec, "header.stamp.nanosec") ||
            !get(h.frameId, "header.frame_id"))
            return false;
        if (sec < 0)
        {
            why_ = "header.stamp.sec is negative (" + std::to_string(sec) + ")";
            return false;
        }
        h.seq = 0, h.stampSec = uint32_t(sec);
        return true;
    }
    bool done()
    {
        const size_t used = cdr_.getSerializedDataLength();
        if (len_ - used <= 3) return true;  // writers may pad the message to 4 bytes
        why_ = std::to_string(len_ - used) + " bytes left over after the last field (at " +
               std::to_string(used) + ")";
        return false;
    }
    const std::string& why() const { return why_; }

private:
    template <typename F>
    bool read(const char* what, F&& f)
    {
        const size_t at = cdr_.getSerializedDataLength();
        try
        {
            f();
            return true;
        }
        catch (const eprosima::fastcdr::exception::Exception& e)
        {
            why_ = std::string(what) + " at byte " + std::to_string(at) + " of " +
                   std::to_string(len_) + ": " + e.what();
            return false;
        }
    }
    static std::string hex(uint8_t b)
    {
        const char* digits = "0123456789abcdef";
        return {digits[b >> 4], digits[b & 15]};
    }
    eprosima::fastcdr::FastBuffer buffer_;
    eprosima::fastcdr::Cdr cdr_;
    const uint8_t* data_;
    size_t len_;
    std::string why_;
};
}  // namespace

const MessageType& wifiType()
{
    static const MessageType t{
        "rf_msgs/msg/Wifi", withDependencies(ros2FieldLines(ros1::wifiFieldLines()))};
    return t;
}

const MessageType& bearingType()
{
    static const MessageType t{
        "rf_msgs/msg/Bearing", withDependencies(ros2FieldLines(ros1::bearingFieldLines()))};
    return t;
}

bool sameDefinition(const MessageType& type, const std::string& definition, std::string& why)
{
    const auto expected = parseDefinition(type.definition, type.name);
    const auto given = parseDefinition(definition, type.name);
    return compareType(canonicalType(type.name, ""), expected, given, why);
}

std::vector<uint8_t> serializeCdr(const ros1::WifiMessage& m)
{
    CdrWriter w(
        kCdrOverhead + m.header.frameId.size() + m.txmac.size() +
        8 * (m.csiReal.size() + m.csiImag.size()) + m.rxId.size());
    w.putHeader(m.header);
    w << m.apId << m.txmac << m.chan << m.nSub << m.nRows << m.nCols << m.bw << m.mcs << m.rssi
      << m.fc << m.seqNum << m.csiReal << m.csiImag << m.rxId << m.msgId;
    return w.take();
}

std::vector<uint8_t> serializeCdr(const ros1::BearingMessage& m)
{
    CdrWriter w(
        kCdrOverhead + m.header.frameId.size() + m.txmac.size() + 4 * m.rssi.size() +
        8 * m.aoa.size());
    w.putHeader(m.header);
    w << m.apId << m.txmac << m.nTx << m.nRx << m.seq << m.rssi << m.aoa;
    return w.take();
}

bool deserializeCdr(const uint8_t* data, size_t len, ros1::WifiMessage& m, std::string& why)
{
    CdrReader r(data, len);
    const bool ok = r.encapsulation() && r.getHeader(m.header) && r.get(m.apId, "ap_id") &&
                    r.get(m.txmac, "txmac") && r.get(m.chan, "chan") && r.get(m.nSub, "n_sub") &&
                    r.get(m.nRows, "n_rows") && r.get(m.nCols, "n_cols") && r.get(m.bw, "bw") &&
                    r.get(m.mcs, "mcs") && r.get(m.rssi, "rssi") && r.get(m.fc, "fc") &&
                    r.get(m.seqNum, "seq_num") && r.get(m.csiReal, "csi_real") &&
                    r.get(m.csiImag, "csi_imag") && r.get(m.rxId, "rx_id") &&
                    r.get(m.msgId, "msg_id") && r.done();
    if (!ok) why = r.why();
    return ok;
}

bool deserializeCdr(const uint8_t* data, size_t len, ros1::BearingMessage& m, std::string& why)
{
    CdrReader r(data, len);
    const bool ok = r.encapsulation() && r.getHeader(m.header) && r.get(m.apId, "ap_id") &&
                    r.get(m.txmac, "txmac") && r.get(m.nTx, "n_tx") && r.get(m.nRx, "n_rx") &&
                    r.get(m.seq, "seq") && r.get(m.rssi, "rssi") && r.get(m.aoa, "aoa") && r.done();
    if (!ok) why = r.why();
    return ok;
}

}  // namespace mrpt_wifi::ros2
