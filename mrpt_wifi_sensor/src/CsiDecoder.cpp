/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/Rosbag2Reader.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>

namespace mrpt_wifi
{
namespace
{
std::mutex& registryMutex()
{
    static std::mutex m;
    return m;
}
constexpr size_t kProbeBytes = 4096;
}  // namespace

uint64_t CsiDecodeSummary::rejectedRecords() const
{
    uint64_t n = 0;
    for (const auto& r : rejected) n += r.count;
    return n;
}

void CsiDecodeSummary::noteOnce(const std::string& note)
{
    if (std::find(notes.begin(), notes.end(), note) == notes.end()) notes.push_back(note);
}

std::string CsiDecodeSummary::asString() const
{
    std::ostringstream o;
    o << "format: " << format << ", records " << records;
    if (skipped) o << " (" << skipped << " without CSI skipped)";
    if (!details.empty()) o << "\n" << details;
    for (const auto& n : notes) o << "\nnote: " << n;
    for (const auto& r : rejected)
        o << "\nskipped " << r.count << " malformed record" << (r.count == 1 ? "" : "s") << ": "
          << r.reason << " (first at " << r.firstWhere << ")";
    o << "\nCSI frames: " << frames;
    return o.str();
}

const char* const kStrictOptionHelp =
    "Stop at the first malformed record (exit 1; what came before is kept) instead of skipping "
    "it: by default malformed records are skipped and counted by reason, the file is finished, "
    "and the exit status is 3 when anything was skipped";

int conversionExitStatus(int rc, const CsiDecodeSummary& summary, const std::string& program)
{
    if (rc != 0 || summary.rejectedRecords() == 0) return rc;
    std::cerr << program << ": " << summary.rejectedRecords()
              << " malformed records skipped (listed above; --strict stops at the first)\n";
    return cli::kExitRecordsSkipped;
}

void rejectRecord(
    const std::string& path, const std::string& format, const CsiDecodeOptions& options,
    CsiDecodeSummary& summary, uint64_t offset, const std::string& reason,
    const std::string& detail, const std::string& where)
{
    const std::string what =
        (where.empty() ? "" : where + ": ") + (detail.empty() ? reason : reason + ": " + detail);
    if (options.strict) throw CsiDecodeError(path, offset, format, what);
    for (auto& r : summary.rejected)
        if (r.reason == reason)
        {
            ++r.count;
            return;
        }
    CsiRejectedRecords r;
    r.reason = reason;
    r.count = 1;
    r.firstOffset = offset;
    r.firstWhere = (where.empty() ? "byte " + std::to_string(offset) : where) +
                   (detail.empty() ? "" : ", " + detail);
    summary.rejected.push_back(r);
}

CsiDecodeError::CsiDecodeError(
    const std::string& file, uint64_t at, const std::string& fmt, const std::string& what)
    : std::runtime_error(
          "'" + file + "' at byte " + std::to_string(at) + " (" + fmt + " format): " + what),
      path(file),
      offset(at),
      format(fmt)
{
}

CsiDecoderRegistry& CsiDecoderRegistry::instance()
{
    static CsiDecoderRegistry r;
    return r;
}

void CsiDecoderRegistry::add(std::shared_ptr<const CsiDecoder> decoder)
{
    std::lock_guard<std::mutex> lock(registryMutex());
    decoders_.push_back(std::move(decoder));
    std::sort(
        decoders_.begin(), decoders_.end(),
        [](const auto& a, const auto& b) { return a->name() < b->name(); });
}

std::shared_ptr<const CsiDecoder> CsiDecoderRegistry::find(const std::string& name) const
{
    std::lock_guard<std::mutex> lock(registryMutex());
    for (const auto& d : decoders_)
        if (d->name() == name) return d;
    return nullptr;
}

std::vector<std::shared_ptr<const CsiDecoder>> CsiDecoderRegistry::all() const
{
    std::lock_guard<std::mutex> lock(registryMutex());
    return decoders_;
}

std::string CsiDecoderRegistry::names(const std::string& separator) const
{
    std::string s;
    for (const auto& d : all()) s += (s.empty() ? "" : separator) + d->name();
    return s;
}

std::shared_ptr<const CsiDecoder> CsiDecoderRegistry::detect(const std::string& path) const
{
    // A ROS 2 bag is the one input that may be a directory (metadata.yaml and its files).
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
    {
        if (auto bag = find("rosbag2"); bag && ros2::looksLikeRosbag2(path)) return bag;
        throw std::runtime_error(
            "'" + path +
            "' is a directory without a ROS 2 bag (metadata.yaml, .mcap or .db3 files)");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open '" + path + "'");
    std::vector<uint8_t> head(kProbeBytes);
    in.read(reinterpret_cast<char*>(head.data()), std::streamsize(head.size()));
    head.resize(size_t(in.gcount()));
    if (head.size() < 4)
        throw std::runtime_error("'" + path + "' is empty or shorter than 4 bytes");
    std::shared_ptr<const CsiDecoder> best;
    int bestScore = 0;
    for (const auto& d : all())
    {
        const int score = d->probe(head.data(), head.size());
        if (score > bestScore)
        {
            bestScore = score;
            best = d;
        }
    }
    if (!best)
        throw std::runtime_error(
            "'" + path + "' is in no CSI format this program reads (" + names(", ") +
            "); give --format to force one");
    return best;
}

std::shared_ptr<const CsiDecoder> decodeCsiFile(
    const std::string& path, const std::string& format, const CsiDecodeOptions& options,
    const CsiFrameSink& onFrame, const CsiProgress& onProgress, CsiDecodeSummary* summaryOut)
{
    auto& registry = CsiDecoderRegistry::instance();
    std::shared_ptr<const CsiDecoder> decoder;
    if (format.empty() || format == "auto")
        decoder = registry.detect(path);
    else if (!(decoder = registry.find(format)))
        throw std::invalid_argument(
            "unknown CSI format '" + format + "' (expected auto|" + registry.names() + ")");
    CsiDecodeSummary local;
    CsiDecodeSummary& summary = summaryOut ? *summaryOut : local;
    summary = CsiDecodeSummary{};
    summary.format = decoder->name();
    decoder->decodeFile(path, options, onFrame, onProgress, summary);
    return decoder;
}

std::string applyFormatOption(const std::string& value, CsiDecodeOptions& options)
{
    if (value == "auto" || value.empty()) return "auto";
    if (value == "nexmon" || value == "nexmon-legacy" || value == "ubilocate")
    {
        options.assembler.format = nexmon::formatHintFromString(value);
        return "nexmon";
    }
    if (!CsiDecoderRegistry::instance().find(value))
        throw std::invalid_argument(
            "unknown format '" + value + "' (expected " + formatOptionChoices() + ")");
    return value;
}

std::string formatOptionChoices()
{
    return "auto|" + CsiDecoderRegistry::instance().names() + "|nexmon-legacy|ubilocate";
}

std::vector<uint8_t> readWholeFile(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open '" + path + "'");
    return std::vector<uint8_t>(
        (std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void ProgressThrottle::update(uint64_t done, uint64_t total)
{
    if (!f_ || !total) return;
    const double fraction = std::min(1.0, double(done) / double(total));
    if (fraction - last_ >= 0.01 || fraction >= 1.0)
    {
        last_ = fraction;
        f_(fraction);
    }
}

}  // namespace mrpt_wifi
