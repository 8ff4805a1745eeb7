/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <lz4frame.h>
#include <mrpt_wifi/sensor/McapReader.h>
#include <zstd.h>

#include <cstring>
#include <fstream>

#include "McapFormat.h"

namespace mrpt_wifi::mcap
{
namespace
{
using namespace format;

std::string opcodeName(uint8_t op)
{
    static const char* names[] = {"unknown",    "Header",        "Footer",          "Schema",
                                  "Channel",    "Message",       "Chunk",           "MessageIndex",
                                  "ChunkIndex", "Attachment",    "AttachmentIndex", "Statistics",
                                  "Metadata",   "MetadataIndex", "SummaryOffset",   "DataEnd"};
    return op < sizeof(names) / sizeof(names[0]) ? names[op] : "opcode " + std::to_string(op);
}

std::string hex32(uint32_t v)
{
    char b[11];
    std::snprintf(b, sizeof(b), "0x%08x", v);
    return b;
}

// Little-endian fields of one record's content; a field running past the content throws
// (caught by the caller, who knows where the record is).
class FieldReader
{
public:
    FieldReader(const uint8_t* d, size_t n) : d_(d), n_(n) {}
    template <typename T>
    T get(const char* what)
    {
        need(sizeof(T), what);
        T v;
        std::memcpy(&v, d_ + pos_, sizeof(T));  // x86/ARM: little-endian as MCAP
        pos_ += sizeof(T);
        return v;
    }
    std::string string(const char* what)
    {
        const auto len = get<uint32_t>(what);
        need(len, what);
        std::string s(reinterpret_cast<const char*>(d_ + pos_), len);
        pos_ += len;
        return s;
    }
    /** A uint32- or uint64-prefixed byte field, in place. */
    template <typename LengthT>
    std::pair<const uint8_t*, size_t> bytes(const char* what)
    {
        const uint64_t len = get<LengthT>(what);
        need(len, what);
        const uint8_t* p = d_ + pos_;
        pos_ += size_t(len);
        return {p, size_t(len)};
    }
    std::map<std::string, std::string> map(const char* what)
    {
        const auto [p, len] = bytes<uint32_t>(what);
        FieldReader inner(p, len);
        std::map<std::string, std::string> m;
        while (inner.pos_ < inner.n_)
        {
            std::string key = inner.string(what);
            m[key] = inner.string(what);
        }
        return m;
    }
    const uint8_t* here() const { return d_ + pos_; }
    size_t left() const { return n_ - pos_; }
    size_t pos() const { return pos_; }

private:
    void need(uint64_t k, const char* what) const
    {
        if (k > n_ - pos_)
            throw std::runtime_error(
                std::string(what) + " needs " + std::to_string(k) + " bytes at byte " +
                std::to_string(pos_) + " of the record, " + std::to_string(n_ - pos_) +
                " are left");
    }
    const uint8_t* d_;
    size_t n_, pos_ = 0;
};

class FileSource : public ByteSource
{
public:
    explicit FileSource(const std::string& path) : path_(path), in_(path, std::ios::binary)
    {
        if (!in_) throw std::runtime_error("cannot open '" + path + "'");
        in_.seekg(0, std::ios::end);
        size_ = uint64_t(in_.tellg());
        in_.seekg(0);
    }
    uint64_t size() const override { return size_; }
    void read(uint64_t offset, size_t n, uint8_t* out) override
    {
        in_.seekg(std::streamoff(offset));
        in_.read(reinterpret_cast<char*>(out), std::streamsize(n));
        if (size_t(in_.gcount()) != n)
            throw McapError(path_, offset, "read error (" + std::to_string(n) + " bytes)");
    }
    const std::string& name() const override { return path_; }

private:
    std::string path_;
    std::ifstream in_;
    uint64_t size_ = 0;
};

class MemorySource : public ByteSource
{
public:
    MemorySource(const uint8_t* d, size_t n, std::string name)
        : d_(d), n_(n), name_(std::move(name))
    {
    }
    uint64_t size() const override { return n_; }
    void read(uint64_t offset, size_t n, uint8_t* out) override
    {
        if (n) std::memcpy(out, d_ + offset, n);
    }
    const std::string& name() const override { return name_; }

private:
    const uint8_t* d_;
    size_t n_;
    std::string name_;
};

class Reader
{
public:
    Reader(
        ByteSource& src, const std::function<void(const MessageView&)>& onMessage,
        McapReadStats& stats, const McapReadOptions& options)
        : src_(src), onMessage_(onMessage), stats_(stats), options_(options)
    {
    }

    void run(const std::function<void(double)>& onProgress)
    {
        const uint64_t size = src_.size();
        uint8_t magic[8];
        if (size < sizeof(magic)) fail(0, "shorter than MCAP's 8-byte magic");
        src_.read(0, sizeof(magic), magic);
        if (std::memcmp(magic, kMagic, sizeof(magic)) != 0)
            fail(0, "does not start with MCAP's magic (\\x89MCAP0\\r\\n)");
        dataCrc_ = crc32Update(0, magic, sizeof(magic));
        uint64_t pos = sizeof(magic);
        uint64_t lastProgress = 0;
        bool first = true;
        while (true)
        {
            if (pos == size)
                fail(
                    pos, std::string("ends without a Footer record (a recording that was cut "
                                     "short?) after ") +
                             std::to_string(stats_.messages) + " messages");
            if (size - pos < kRecordPrefix)
                fail(
                    pos, "truncated: " + std::to_string(size - pos) +
                             " bytes left, a record needs at least 9");
            uint8_t prefix[kRecordPrefix];
            src_.read(pos, kRecordPrefix, prefix);
            const uint8_t op = prefix[0];
            uint64_t len;
            std::memcpy(&len, prefix + 1, 8);
            if (len > size - pos - kRecordPrefix)
                fail(
                    pos, opcodeName(op) + " record of " + std::to_string(len) +
                             " bytes runs past the end of the file (" + std::to_string(size) +
                             " bytes: truncated?)");
            if (first && op != kHeader)
                fail(pos, "the first record is " + opcodeName(op) + ", not Header");
            first = false;
            content_.resize(size_t(len));
            src_.read(pos + kRecordPrefix, size_t(len), content_.data());
            ++stats_.records;
            if (op == kFooter)
            {
                footer(pos);
                const uint64_t end = pos + kRecordPrefix + len;
                if (size - end < sizeof(magic))
                    fail(end, "the closing magic after the Footer is missing (truncated?)");
                src_.read(end, sizeof(magic), magic);
                if (std::memcmp(magic, kMagic, sizeof(magic)) != 0)
                    fail(end, "the closing magic after the Footer is wrong");
                break;
            }
            if (!dataEnded_)
            {
                if (op == kDataEnd)
                    dataEnd(pos);
                else
                {
                    dataCrc_ = crc32Update(dataCrc_, prefix, kRecordPrefix);
                    dataCrc_ = crc32Update(dataCrc_, content_.data(), content_.size());
                    dataRecord(op, pos);
                }
            }
            pos += kRecordPrefix + len;
            if (onProgress && pos - lastProgress > (uint64_t(1) << 20))
                onProgress(double(pos) / double(size)), lastProgress = pos;
        }
        if (onProgress) onProgress(1.0);
    }

private:
    [[noreturn]] void fail(uint64_t offset, const std::string& what)
    {
        throw McapError(src_.name(), offset, what);
    }

    template <typename F>
    void parse(uint64_t offset, const std::string& what, F&& f)
    {
        try
        {
            f();
        }
        catch (const McapError&)
        {
            throw;
        }
        catch (const std::exception& e)
        {
            fail(offset, what + ": " + e.what());
        }
    }

    void dataRecord(uint8_t op, uint64_t pos)
    {
        switch (op)
        {
            case kHeader:
                parse(
                    pos, "Header record",
                    [&]
                    {
                        FieldReader r(content_.data(), content_.size());
                        stats_.profile = r.string("profile");
                        stats_.library = r.string("library");
                    });
                break;
            case kSchema:
            case kChannel:
            case kMessage:
                parse(
                    pos, opcodeName(op) + " record",
                    [&] { record(op, content_.data(), content_.size(), pos, 0, false); });
                deliver(op);
                break;
            case kChunk:
                chunk(pos);
                break;
            case kAttachment:
                parse(pos, "Attachment record", [&] { attachment(pos); });
                break;
            default:
                break;  // indexes, metadata and records of later versions: not needed here
        }
    }

    void record(
        uint8_t op, const uint8_t* d, size_t n, uint64_t filePos, uint64_t chunkPos, bool inChunk)
    {
        FieldReader r(d, n);
        if (op == kSchema)
        {
            Schema s;
            s.id = r.get<uint16_t>("schema id");
            s.name = r.string("schema name");
            s.encoding = r.string("schema encoding");
            const auto [p, len] = r.bytes<uint32_t>("schema data");
            s.data.assign(p, p + len);
            if (s.id != 0) schemas_[s.id] = std::move(s);  // id 0 is invalid: ignored
        }
        else if (op == kChannel)
        {
            Channel c;
            c.id = r.get<uint16_t>("channel id");
            c.schemaId = r.get<uint16_t>("channel schema id");
            c.topic = r.string("channel topic");
            c.messageEncoding = r.string("channel message encoding");
            c.metadata = r.map("channel metadata");
            channels_[c.id] = std::move(c);
        }
        else if (op == kMessage)
        {
            MessageView m;
            const uint16_t channelId = r.get<uint16_t>("message channel id");
            m.sequence = r.get<uint32_t>("message sequence");
            m.logTime = r.get<uint64_t>("message log time");
            m.publishTime = r.get<uint64_t>("message publish time");
            m.data = r.here(), m.size = r.left();
            m.fileOffset = filePos, m.chunkOffset = chunkPos, m.inChunk = inChunk;
            if (const auto c = channels_.find(channelId); c != channels_.end())
            {
                m.channel = &c->second;
                if (const auto s = schemas_.find(c->second.schemaId); s != schemas_.end())
                    m.schema = &s->second;
            }
            else
            {
                // A message before its channel: the decoder counts it as malformed.
                unknownChannel_.id = channelId;
                unknownChannel_.topic = "(channel " + std::to_string(channelId) + " not defined)";
                m.channel = &unknownChannel_;
            }
            pending_ = m;
        }
    }

    // Outside parse(): what the caller's callback throws is its own, not a parse error.
    void deliver(uint8_t op)
    {
        if (op != kMessage) return;
        ++stats_.messages;
        onMessage_(pending_);
    }

    void chunk(uint64_t pos)
    {
        uint64_t uncompressedSize = 0;
        uint32_t uncompressedCrc = 0;
        std::string compression;
        const uint8_t* compressed = nullptr;
        size_t compressedSize = 0;
        parse(
            pos, "Chunk record",
            [&]
            {
                FieldReader r(content_.data(), content_.size());
                r.get<uint64_t>("chunk start time");
                r.get<uint64_t>("chunk end time");
                uncompressedSize = r.get<uint64_t>("chunk uncompressed size");
                uncompressedCrc = r.get<uint32_t>("chunk uncompressed crc");
                compression = r.string("chunk compression");
                std::tie(compressed, compressedSize) = r.bytes<uint64_t>("chunk records");
            });
        ++stats_.chunks;
        ++stats_.chunksByCompression[compression];
        if (uncompressedSize > options_.maxChunkBytes)
            fail(
                pos, "Chunk claims " + std::to_string(uncompressedSize) +
                         " uncompressed bytes, more than the " +
                         std::to_string(options_.maxChunkBytes) + " this reader accepts");
        const uint8_t* records = nullptr;
        if (compression.empty())
        {
            if (compressedSize != uncompressedSize)
                fail(
                    pos, "uncompressed Chunk of " + std::to_string(compressedSize) +
                             " bytes says it holds " + std::to_string(uncompressedSize));
            records = compressed;
        }
        else
        {
            chunkBytes_.resize(size_t(uncompressedSize));
            if (compression == "zstd")
                unzstd(pos, compressed, compressedSize);
            else if (compression == "lz4")
                unlz4(pos, compressed, compressedSize);
            else
                fail(
                    pos, "Chunk compressed with '" + compression +
                             "' (this reader knows zstd, lz4 and none)");
            records = chunkBytes_.data();
        }
        if (uncompressedCrc != 0)
        {
            const uint32_t crc = crc32Update(0, records, size_t(uncompressedSize));
            if (crc != uncompressedCrc)
                fail(
                    pos, "Chunk CRC mismatch: records have " + hex32(crc) + ", the chunk says " +
                             hex32(uncompressedCrc));
            ++stats_.crcsChecked;
        }
        // The chunk's records: schemas, channels and messages.
        uint64_t at = 0;
        while (at < uncompressedSize)
        {
            const auto where = [&]
            { return "in the Chunk, at byte " + std::to_string(at) + " of its records"; };
            if (uncompressedSize - at < kRecordPrefix) fail(pos, "truncated record " + where());
            const uint8_t op = records[at];
            uint64_t len;
            std::memcpy(&len, records + at + 1, 8);
            if (len > uncompressedSize - at - kRecordPrefix)
                fail(
                    pos, opcodeName(op) + " record of " + std::to_string(len) +
                             " bytes runs past the chunk's end " + where());
            if (op == kSchema || op == kChannel || op == kMessage)
            {
                parse(
                    pos, opcodeName(op) + " record " + where(),
                    [&] { record(op, records + at + kRecordPrefix, size_t(len), pos, at, true); });
                deliver(op);
            }
            at += kRecordPrefix + len;
        }
    }

    void unzstd(uint64_t pos, const uint8_t* src, size_t n)
    {
        const size_t got = ZSTD_decompress(chunkBytes_.data(), chunkBytes_.size(), src, n);
        if (ZSTD_isError(got))
            fail(pos, std::string("zstd Chunk does not decompress: ") + ZSTD_getErrorName(got));
        if (got != chunkBytes_.size())
            fail(
                pos, "zstd Chunk decompresses to " + std::to_string(got) + " bytes, it says " +
                         std::to_string(chunkBytes_.size()));
    }

    void unlz4(uint64_t pos, const uint8_t* src, size_t n)
    {
        LZ4F_dctx* ctx = nullptr;
        if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
            fail(pos, "lz4: cannot create a decompression context");
        std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> guard(
            ctx, &LZ4F_freeDecompressionContext);
        size_t in = 0, out = 0;
        while (true)
        {
            size_t srcSize = n - in, dstSize = chunkBytes_.size() - out;
            const size_t hint = LZ4F_decompress(
                ctx, chunkBytes_.data() + out, &dstSize, src + in, &srcSize, nullptr);
            if (LZ4F_isError(hint))
                fail(pos, std::string("lz4 Chunk does not decompress: ") + LZ4F_getErrorName(hint));
            in += srcSize, out += dstSize;
            if (hint == 0) break;  // frame complete
            if (srcSize == 0 && dstSize == 0)
                fail(
                    pos, "lz4 Chunk ends inside its frame, or decompresses to more than the " +
                             std::to_string(chunkBytes_.size()) + " bytes it says");
        }
        if (out != chunkBytes_.size())
            fail(
                pos, "lz4 Chunk decompresses to " + std::to_string(out) + " bytes, it says " +
                         std::to_string(chunkBytes_.size()));
    }

    void attachment(uint64_t pos)
    {
        FieldReader r(content_.data(), content_.size());
        r.get<uint64_t>("attachment log time");
        r.get<uint64_t>("attachment create time");
        r.string("attachment name");
        r.string("attachment media type");
        r.bytes<uint64_t>("attachment data");
        const size_t covered = r.pos();
        const uint32_t crc = r.get<uint32_t>("attachment crc");
        if (crc == 0) return;
        const uint32_t have = crc32Update(0, content_.data(), covered);
        if (have != crc)
            fail(
                pos, "Attachment CRC mismatch: " + hex32(have) + ", the record says " + hex32(crc));
        ++stats_.crcsChecked;
    }

    void dataEnd(uint64_t pos)
    {
        dataEnded_ = true;
        stats_.hasDataEnd = true;
        uint32_t crc = 0;
        parse(
            pos, "DataEnd record",
            [&]
            {
                FieldReader r(content_.data(), content_.size());
                crc = r.get<uint32_t>("data section crc");
            });
        if (crc == 0) return;
        if (crc != dataCrc_)
            fail(
                pos, "data section CRC mismatch: the bytes before DataEnd have " + hex32(dataCrc_) +
                         ", DataEnd says " + hex32(crc));
        ++stats_.crcsChecked;
    }

    void footer(uint64_t pos)
    {
        stats_.hasFooter = true;
        uint64_t summaryStart = 0;
        uint32_t crc = 0;
        parse(
            pos, "Footer record",
            [&]
            {
                FieldReader r(content_.data(), content_.size());
                summaryStart = r.get<uint64_t>("summary start");
                r.get<uint64_t>("summary offset start");
                crc = r.get<uint32_t>("summary crc");
            });
        stats_.hasSummary = summaryStart != 0;
        if (summaryStart == 0 || crc == 0) return;
        // The summary CRC covers the summary through the Footer's fields before the CRC.
        const uint64_t end = pos + kRecordPrefix + 16;
        if (summaryStart >= pos)
            fail(
                pos, "the Footer's summary start " + std::to_string(summaryStart) +
                         " is not before the Footer");
        std::vector<uint8_t> bytes(size_t(end - summaryStart));
        src_.read(summaryStart, bytes.size(), bytes.data());
        const uint32_t have = crc32Update(0, bytes.data(), bytes.size());
        if (have != crc)
            fail(pos, "summary CRC mismatch: " + hex32(have) + ", the Footer says " + hex32(crc));
        ++stats_.crcsChecked;
    }

    ByteSource& src_;
    const std::function<void(const MessageView&)>& onMessage_;
    McapReadStats& stats_;
    const McapReadOptions& options_;
    std::map<uint16_t, Schema> schemas_;
    std::map<uint16_t, Channel> channels_;
    Channel unknownChannel_;
    MessageView pending_;
    std::vector<uint8_t> content_, chunkBytes_;
    uint32_t dataCrc_ = 0;
    bool dataEnded_ = false;
};
}  // namespace

McapError::McapError(const std::string& name, uint64_t off, const std::string& what)
    : std::runtime_error("'" + name + "' at byte " + std::to_string(off) + ": " + what), offset(off)
{
}

std::unique_ptr<ByteSource> openFileSource(const std::string& path)
{
    return std::make_unique<FileSource>(path);
}

std::unique_ptr<ByteSource> memorySource(const uint8_t* data, size_t len, const std::string& name)
{
    return std::make_unique<MemorySource>(data, len, name);
}

bool hasMcapMagic(const uint8_t* head, size_t len)
{
    return len >= sizeof(kMagic) && std::memcmp(head, kMagic, sizeof(kMagic)) == 0;
}

void readMcap(
    ByteSource& source, const std::function<void(const MessageView&)>& onMessage,
    const std::function<void(double)>& onProgress, McapReadStats* statsOut,
    const McapReadOptions& options)
{
    McapReadStats local;
    McapReadStats& stats = statsOut ? *statsOut : local;
    stats = McapReadStats{};
    Reader(source, onMessage, stats, options).run(onProgress);
}

}  // namespace mrpt_wifi::mcap
