/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/containers/yaml.h>
#include <mrpt_wifi/sensor/McapReader.h>
#include <mrpt_wifi/sensor/Rosbag2Reader.h>
#include <sqlite3.h>
#include <zstd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace mrpt_wifi::ros2
{
namespace
{
bool endsWith(const std::string& s, const std::string& tail)
{
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

bool isStorageFile(const std::string& name)
{
    return endsWith(name, ".mcap") || endsWith(name, ".db3");
}

std::string timeText(uint64_t ns)
{
    std::ostringstream o;
    o.precision(9);
    o << std::fixed << double(ns) * 1e-9;
    return o.str();
}

// How rosbag2 compressed a bag (metadata.yaml): "" / "FILE" / "MESSAGE", and the format.
struct BagCompression
{
    std::string mode, format;
};

BagCompression compressionOf(const std::string& dir)
{
    BagCompression c;
    const fs::path meta = fs::path(dir) / "metadata.yaml";
    if (!fs::exists(meta)) return c;
    try
    {
        const auto y = mrpt::containers::yaml::FromFile(meta.string());
        const auto info = y["rosbag2_bagfile_information"];
        c.mode = info.getOrDefault<std::string>("compression_mode", "");
        c.format = info.getOrDefault<std::string>("compression_format", "");
    }
    catch (const std::exception& e)
    {
        throw std::runtime_error("'" + meta.string() + "' is not rosbag2 metadata: " + e.what());
    }
    std::transform(c.mode.begin(), c.mode.end(), c.mode.begin(), ::toupper);
    return c;
}

// Messages rosbag2 compressed one by one (compression_mode MESSAGE).
class MessageDecompressor
{
public:
    explicit MessageDecompressor(BagCompression c) : c_(std::move(c)) {}
    bool active() const { return c_.mode == "MESSAGE"; }
    /** The decompressed bytes, or throws naming `where`. */
    const std::vector<uint8_t>& run(const uint8_t* d, size_t n, const std::string& where)
    {
        if (c_.format != "zstd")
            throw std::runtime_error(
                where + ": messages compressed with '" + c_.format + "' (this reader knows zstd)");
        const auto size = ZSTD_getFrameContentSize(d, n);
        if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN ||
            size > (uint64_t(1) << 28))
            throw std::runtime_error(where + ": not a zstd frame with a known size");
        out_.resize(size_t(size));
        const size_t got = ZSTD_decompress(out_.data(), out_.size(), d, n);
        if (ZSTD_isError(got) || got != out_.size())
            throw std::runtime_error(where + ": zstd message does not decompress");
        return out_;
    }

private:
    BagCompression c_;
    std::vector<uint8_t> out_;
};

// ---- MCAP
void readMcapBag(
    mcap::ByteSource& source, const std::function<void(const BagMessage&)>& onMessage,
    const std::function<void(double)>& onProgress, BagReadStats& stats,
    MessageDecompressor* decompressor, const mcap::McapReadOptions& options = {})
{
    mcap::McapReadStats ms;
    const auto deliver = [&](const mcap::MessageView& m)
    {
        BagMessage b;
        b.file = source.name();
        b.topic = m.channel->topic;
        b.serializationFormat = m.channel->messageEncoding;
        if (m.schema)
        {
            b.type = m.schema->name;
            b.definitionEncoding = m.schema->encoding;
        }
        // Schemas are small next to a CSI message: copied for each message, not tracked.
        std::string definition;
        if (m.schema)
        {
            definition.assign(m.schema->data.begin(), m.schema->data.end());
            b.definition = &definition;
        }
        b.timeNs = m.logTime;
        b.data = m.data, b.size = m.size;
        b.offset = m.fileOffset;
        b.where = (m.inChunk ? "message in the chunk at byte " + std::to_string(m.fileOffset) +
                                   " (its record at byte " + std::to_string(m.chunkOffset) + ")"
                             : "message at byte " + std::to_string(m.fileOffset)) +
                  " (" + b.topic + ", t=" + timeText(m.logTime) + ")";
        if (decompressor && decompressor->active())
        {
            const auto& plain = decompressor->run(m.data, m.size, b.where);
            b.data = plain.data(), b.size = plain.size();
        }
        ++stats.messages;
        onMessage(b);
    };
    const auto account = [&]
    {
        for (const auto& [c, n] : ms.chunksByCompression)
            stats.mcapChunks[c.empty() ? "none" : c] += n;
        stats.crcsChecked += ms.crcsChecked;
        if (ms.hasFooter && !ms.hasSummary) ++stats.mcapWithoutSummary;
    };
    try
    {
        mcap::readMcap(source, deliver, onProgress, &ms, options);
    }
    catch (...)
    {
        account();
        throw;
    }
    account();
}

// ---- SQLite
class Sqlite
{
public:
    explicit Sqlite(const std::string& path) : path_(path)
    {
        if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
        {
            const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
            sqlite3_close(db_);
            throw std::runtime_error("cannot open '" + path + "' as SQLite: " + why);
        }
    }
    ~Sqlite() { sqlite3_close(db_); }
    Sqlite(const Sqlite&) = delete;
    Sqlite& operator=(const Sqlite&) = delete;

    class Statement
    {
    public:
        Statement(Sqlite& db, const std::string& sql) : db_(db)
        {
            if (sqlite3_prepare_v2(db.db_, sql.c_str(), -1, &s_, nullptr) != SQLITE_OK)
                db.fail("cannot query (" + sql + ")");
        }
        ~Statement() { sqlite3_finalize(s_); }
        Statement(const Statement&) = delete;
        Statement& operator=(const Statement&) = delete;
        /** True for a row, false at the end; throws on an error (e.g. a corrupt page). */
        bool step(const std::string& context)
        {
            const int rc = sqlite3_step(s_);
            if (rc == SQLITE_ROW) return true;
            if (rc == SQLITE_DONE) return false;
            db_.fail(context);
        }
        int64_t integer(int col) { return sqlite3_column_int64(s_, col); }
        std::string text(int col)
        {
            const auto* p = sqlite3_column_text(s_, col);
            return p ? std::string(
                           reinterpret_cast<const char*>(p), size_t(sqlite3_column_bytes(s_, col)))
                     : std::string();
        }
        std::pair<const uint8_t*, size_t> blob(int col)
        {
            const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(s_, col));
            return {p, size_t(sqlite3_column_bytes(s_, col))};
        }

    private:
        Sqlite& db_;
        sqlite3_stmt* s_ = nullptr;
    };

    bool hasTable(const std::string& name)
    {
        Statement s(
            *this, "SELECT 1 FROM sqlite_master WHERE type='table' AND name='" + name + "'");
        return s.step("reading the table list");
    }
    [[noreturn]] void fail(const std::string& context)
    {
        throw std::runtime_error("'" + path_ + "': " + context + ": " + sqlite3_errmsg(db_));
    }

private:
    std::string path_;
    sqlite3* db_ = nullptr;
};

void readSqliteBag(
    const std::string& path, const std::function<void(const BagMessage&)>& onMessage,
    const std::function<void(double)>& onProgress, BagReadStats& stats,
    MessageDecompressor& decompressor)
{
    Sqlite db(path);
    if (!db.hasTable("topics") || !db.hasTable("messages"))
        throw std::runtime_error(
            "'" + path + "' is an SQLite file without rosbag2's topics and messages tables");
    struct Topic
    {
        std::string name, type, format;
    };
    std::map<int64_t, Topic> topics;
    {
        Sqlite::Statement s(db, "SELECT id, name, type, serialization_format FROM topics");
        while (s.step("reading the topics table"))
            topics[s.integer(0)] = {s.text(1), s.text(2), s.text(3)};
    }
    // Since Iron a bag keeps each type's definition (older ones: the type name alone).
    std::map<std::string, std::pair<std::string, std::string>> definitions;  // type -> enc, text
    if (db.hasTable("message_definitions"))
    {
        Sqlite::Statement s(
            db, "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions");
        while (s.step("reading the message_definitions table"))
            if (!s.text(2).empty()) definitions[s.text(0)] = {s.text(1), s.text(2)};
    }
    int64_t total = 0;
    {
        Sqlite::Statement s(db, "SELECT COUNT(*) FROM messages");
        if (s.step("counting messages")) total = s.integer(0);
    }
    Sqlite::Statement s(
        db, "SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
    int64_t done = 0, lastId = -1;
    const Topic unknown{"", "", ""};
    while (s.step(
        lastId < 0 ? "reading the first message"
                   : "reading the message after id " + std::to_string(lastId)))
    {
        lastId = s.integer(0);
        const auto t = topics.find(s.integer(1));
        const Topic& topic = t != topics.end() ? t->second : unknown;
        BagMessage b;
        b.file = path;
        b.topic = t != topics.end() ? topic.name
                                    : "(topic id " + std::to_string(s.integer(1)) + " not defined)";
        b.type = topic.type;
        b.serializationFormat = topic.format;
        if (const auto d = definitions.find(topic.type); d != definitions.end())
            b.definitionEncoding = d->second.first, b.definition = &d->second.second;
        b.timeNs = uint64_t(std::max<int64_t>(0, s.integer(2)));
        std::tie(b.data, b.size) = s.blob(3);
        b.offset = uint64_t(lastId);
        b.where = "message id " + std::to_string(lastId) + " (" + b.topic +
                  ", t=" + timeText(b.timeNs) + ")";
        if (decompressor.active())
        {
            const auto& plain = decompressor.run(b.data, b.size, "'" + path + "' " + b.where);
            b.data = plain.data(), b.size = plain.size();
        }
        ++stats.messages;
        onMessage(b);
        if (onProgress && total > 0 && (++done % 256 == 0))
            onProgress(double(done) / double(total));
    }
    if (onProgress) onProgress(1.0);
}
}  // namespace

std::string BagReadStats::asString() const
{
    std::ostringstream o;
    o << files.size() << " storage file" << (files.size() == 1 ? "" : "s") << ", " << messages
      << " messages";
    if (!mcapChunks.empty())
    {
        o << "; MCAP chunks:";
        for (const auto& [c, n] : mcapChunks) o << " " << c << " " << n;
    }
    if (crcsChecked) o << "; " << crcsChecked << " CRCs checked";
    if (mcapWithoutSummary) o << "; " << mcapWithoutSummary << " MCAP without summary";
    return o.str();
}

bool looksLikeRosbag2(const std::string& path)
{
    std::error_code ec;
    if (fs::is_directory(path, ec))
    {
        if (fs::exists(fs::path(path) / "metadata.yaml", ec)) return true;
        for (const auto& e : fs::directory_iterator(path, ec))
            if (e.is_regular_file(ec) && isStorageFile(e.path().filename().string())) return true;
        return false;
    }
    return isStorageFile(path);
}

std::vector<std::string> bagFiles(const std::string& path)
{
    if (!fs::is_directory(path))
    {
        if (!fs::exists(path)) throw std::runtime_error("cannot open '" + path + "'");
        return {path};
    }
    std::vector<std::string> files;
    const fs::path meta = fs::path(path) / "metadata.yaml";
    if (fs::exists(meta))
    {
        const auto compression = compressionOf(path);
        try
        {
            const auto y = mrpt::containers::yaml::FromFile(meta.string());
            const auto info = y["rosbag2_bagfile_information"];
            if (info.has("relative_file_paths"))
                for (const auto& f : info["relative_file_paths"].asSequence())
                    files.push_back((fs::path(path) / f.as<std::string>()).string());
        }
        catch (const std::exception& e)
        {
            throw std::runtime_error(
                "'" + meta.string() + "' is not rosbag2 metadata: " + e.what());
        }
        if (compression.mode == "FILE")
            throw std::runtime_error(
                "'" + path + "': rosbag2 compressed its files as a whole (" + compression.format +
                "); decompress them first (ros2 bag decompress, or zstd -d and edit "
                "metadata.yaml)");
        for (const auto& f : files)
            if (!fs::exists(f))
                throw std::runtime_error(
                    "'" + f + "', listed in '" + meta.string() + "', does not exist");
    }
    if (files.empty())
    {
        for (const auto& e : fs::directory_iterator(path))
            if (e.is_regular_file() && isStorageFile(e.path().filename().string()))
                files.push_back(e.path().string());
        // bag_2 before bag_10: by length first, then by name.
        std::sort(
            files.begin(), files.end(),
            [](const std::string& a, const std::string& b)
            { return a.size() != b.size() ? a.size() < b.size() : a < b; });
    }
    if (files.empty())
        throw std::runtime_error("'" + path + "' holds no rosbag2 storage file (.mcap, .db3)");
    return files;
}

void forEachBagMessage(
    const std::string& path, const std::function<void(const BagMessage&)>& onMessage,
    const std::function<void(double)>& onProgress, BagReadStats* statsOut)
{
    BagReadStats local;
    BagReadStats& stats = statsOut ? *statsOut : local;
    stats = BagReadStats{};
    const auto files = bagFiles(path);
    MessageDecompressor decompressor(
        fs::is_directory(path) ? compressionOf(path) : BagCompression{});
    for (size_t i = 0; i < files.size(); ++i)
    {
        const auto& f = files[i];
        stats.files.push_back(f);
        const auto progress = [&](double x)
        {
            if (onProgress) onProgress((double(i) + x) / double(files.size()));
        };
        // By content: an MCAP file starts with its magic, anything else is tried as SQLite.
        uint8_t head[8] = {};
        {
            std::ifstream in(f, std::ios::binary);
            if (!in) throw std::runtime_error("cannot open '" + f + "'");
            in.read(reinterpret_cast<char*>(head), sizeof(head));
        }
        if (mcap::hasMcapMagic(head, sizeof(head)))
        {
            auto source = mcap::openFileSource(f);
            readMcapBag(*source, onMessage, progress, stats, &decompressor);
        }
        else
            readSqliteBag(f, onMessage, progress, stats, decompressor);
    }
}

void forEachMcapBagMessage(
    const uint8_t* data, size_t len, const std::string& name,
    const std::function<void(const BagMessage&)>& onMessage, BagReadStats* statsOut,
    const mcap::McapReadOptions& options)
{
    BagReadStats local;
    BagReadStats& stats = statsOut ? *statsOut : local;
    stats = BagReadStats{};
    stats.files.push_back(name);
    auto source = mcap::memorySource(data, len, name);
    readMcapBag(*source, onMessage, {}, stats, nullptr, options);
}

}  // namespace mrpt_wifi::ros2
