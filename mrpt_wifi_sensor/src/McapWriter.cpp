/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <lz4frame.h>
#include <mrpt_wifi/sensor/McapWriter.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <stdexcept>

#include "McapFormat.h"

namespace mrpt_wifi::mcap
{
namespace
{
using namespace format;

/** Little-endian record fields, as the specification lays them out. */
class Bytes
{
public:
    std::vector<uint8_t> b;
    template <class T>
    void le(T v)
    {
        for (size_t i = 0; i < sizeof(T); ++i) b.push_back(uint8_t(uint64_t(v) >> (8 * i)));
    }
    void u8(uint8_t v) { b.push_back(v); }
    void u16(uint16_t v) { le(v); }
    void u32(uint32_t v) { le(v); }
    void u64(uint64_t v) { le(v); }
    void raw(const void* p, size_t n)
    {
        const auto* c = static_cast<const uint8_t*>(p);
        b.insert(b.end(), c, c + n);
    }
    void str(const std::string& s)
    {
        u32(uint32_t(s.size()));
        raw(s.data(), s.size());
    }
    void map(const std::map<std::string, std::string>& m)
    {
        Bytes entries;
        for (const auto& [k, v] : m) entries.str(k), entries.str(v);
        u32(uint32_t(entries.b.size()));
        raw(entries.b.data(), entries.b.size());
    }
    /** <opcode><uint64 length><content> */
    void record(uint8_t opcode, const Bytes& content)
    {
        u8(opcode);
        u64(content.b.size());
        raw(content.b.data(), content.b.size());
    }
};

std::vector<uint8_t> compressZstd(const std::vector<uint8_t>& in)
{
    std::vector<uint8_t> out(ZSTD_compressBound(in.size()));
    // Level 1: rosbag2's "fastest" preset; CSI compresses little better at higher levels.
    const size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1);
    if (ZSTD_isError(n))
        throw std::runtime_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(n));
    out.resize(n);
    return out;
}

std::vector<uint8_t> compressLz4(const std::vector<uint8_t>& in)
{
    // MCAP's "lz4" is the LZ4 frame format.
    LZ4F_preferences_t prefs;
    std::memset(&prefs, 0, sizeof(prefs));
    prefs.frameInfo.contentSize = in.size();
    std::vector<uint8_t> out(LZ4F_compressFrameBound(in.size(), &prefs));
    const size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
    if (LZ4F_isError(n))
        throw std::runtime_error(std::string("lz4 compression failed: ") + LZ4F_getErrorName(n));
    out.resize(n);
    return out;
}

const char* compressionName(Compression c)
{
    switch (c)
    {
        case Compression::Zstd:
            return "zstd";
        case Compression::Lz4:
            return "lz4";
        default:
            return "";
    }
}

// offered_qos_profiles as rosbag2 records it for one publisher (reliable, volatile; history
// and depth unknown; deadline, lifespan and lease infinite), so `ros2 bag play` has a profile.
const char* kOfferedQos =
    "- history: 3\n"
    "  depth: 0\n"
    "  reliability: 1\n"
    "  durability: 2\n"
    "  deadline:\n"
    "    sec: 9223372036854775807\n"
    "    nsec: 4294967295\n"
    "  lifespan:\n"
    "    sec: 9223372036854775807\n"
    "    nsec: 4294967295\n"
    "  liveliness: 1\n"
    "  liveliness_lease_duration:\n"
    "    sec: 9223372036854775807\n"
    "    nsec: 4294967295\n"
    "  avoid_ros_namespace_conventions: false";
}  // namespace

Compression compressionFromString(const std::string& name)
{
    if (name == "zstd") return Compression::Zstd;
    if (name == "lz4") return Compression::Lz4;
    if (name == "none") return Compression::None;
    throw std::invalid_argument("unknown MCAP compression '" + name + "' (zstd|lz4|none)");
}

Writer::Writer(const std::string& path, WriterOptions options)
    : path_(path), options_(std::move(options))
{
    file_ = std::fopen(path.c_str(), "wb");
    if (!file_) fail("cannot create");
    Bytes head;
    head.raw(kMagic, sizeof(kMagic));
    Bytes header;
    header.str(options_.profile);
    header.str("mrpt_wifi");
    head.record(kHeader, header);
    writeBytes(head.b);
}

Writer::~Writer()
{
    if (!file_) return;
    try
    {
        close();
    }
    catch (const std::exception& e)
    {
        std::cerr << e.what() << "\n";
        if (file_) std::fclose(file_);
    }
}

void Writer::fail(const std::string& what) const
{
    throw std::runtime_error(what + " '" + path_ + "': " + std::strerror(errno));
}

void Writer::writeBytes(const std::vector<uint8_t>& bytes)
{
    errno = 0;
    if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    {
        failed_ = true;
        fail("writing MCAP file");
    }
    offset_ += bytes.size();
    auto& crc = inSummary_ ? summaryCrc_ : dataCrc_;
    crc = crc32Update(crc, bytes.data(), bytes.size());
}

uint16_t Writer::addSchema(
    const std::string& name, const std::string& encoding, const std::string& data)
{
    for (const auto& s : schemas_)
        if (s.name == name && s.encoding == encoding && s.data == data) return s.id;
    // Id 0 means "no schema" in the specification.
    const auto id = uint16_t(schemas_.size() + 1);
    schemas_.push_back({id, name, encoding, data});
    // Schemas and channels go to the data section outside chunks, before any message that uses
    // them: the open chunk is written later.
    Bytes rec, content;
    content.u16(id);
    content.str(name);
    content.str(encoding);
    content.str(data);  // uint32 length + bytes, the same layout as a string
    rec.record(kSchema, content);
    writeBytes(rec.b);
    return id;
}

uint16_t Writer::addChannel(
    uint16_t schemaId, const std::string& topic, const std::string& messageEncoding,
    const std::map<std::string, std::string>& metadata)
{
    const auto id = uint16_t(channels_.size());
    channels_.push_back({id, schemaId, topic, messageEncoding, metadata});
    Bytes rec, content;
    content.u16(id);
    content.u16(schemaId);
    content.str(topic);
    content.str(messageEncoding);
    content.map(metadata);
    rec.record(kChannel, content);
    writeBytes(rec.b);
    return id;
}

uint16_t Writer::addRos2Channel(
    const std::string& topic, const std::string& typeName, const std::string& definition)
{
    return addChannel(
        addSchema(typeName, "ros2msg", definition), topic, "cdr",
        {{"offered_qos_profiles", kOfferedQos}});
}

void Writer::write(
    uint16_t channelId, uint64_t logTime_ns, uint64_t publishTime_ns, const uint8_t* data,
    size_t size)
{
    if (!file_) throw std::logic_error("MCAP writer for '" + path_ + "' already closed");
    if (channelId >= channels_.size())
        throw std::invalid_argument("MCAP write: no channel " + std::to_string(channelId));
    auto& channel = channels_[channelId];
    if (chunk_.empty()) chunkStart_ = chunkEnd_ = logTime_ns;
    chunkStart_ = std::min(chunkStart_, logTime_ns);
    chunkEnd_ = std::max(chunkEnd_, logTime_ns);
    if (messageCount_ == 0) startTime_ = endTime_ = logTime_ns;
    startTime_ = std::min(startTime_, logTime_ns);
    endTime_ = std::max(endTime_, logTime_ns);
    chunkMessageIndex_[channelId].emplace_back(logTime_ns, chunk_.size());

    Bytes content;
    content.u16(channelId);
    content.u32(channel.nextSequence++);
    content.u64(logTime_ns);
    content.u64(publishTime_ns);
    content.raw(data, size);
    Bytes rec;
    rec.record(kMessage, content);
    chunk_.insert(chunk_.end(), rec.b.begin(), rec.b.end());
    ++channel.messageCount;
    ++messageCount_;
    if (chunk_.size() >= options_.chunkSize) flushChunk();
}

void Writer::flushChunk()
{
    if (chunk_.empty()) return;
    ChunkIndex index;
    index.startTime = chunkStart_;
    index.endTime = chunkEnd_;
    index.chunkStart = offset_;
    index.compression = compressionName(options_.compression);
    index.uncompressedSize = chunk_.size();
    const std::vector<uint8_t> records =
        options_.compression == Compression::Zstd  ? compressZstd(chunk_)
        : options_.compression == Compression::Lz4 ? compressLz4(chunk_)
                                                   : chunk_;
    index.compressedSize = records.size();

    Bytes content;
    content.u64(chunkStart_);
    content.u64(chunkEnd_);
    content.u64(chunk_.size());
    content.u32(crc32Update(0, chunk_.data(), chunk_.size()));
    content.str(index.compression);
    content.u64(records.size());
    Bytes rec;
    rec.u8(kChunk);
    rec.u64(content.b.size() + records.size());
    rec.raw(content.b.data(), content.b.size());
    writeBytes(rec.b);
    writeBytes(records);
    index.chunkLength = offset_ - index.chunkStart;

    // One message index per channel of the chunk, offsets into the uncompressed records.
    const uint64_t indexesStart = offset_;
    for (auto& [channelId, entries] : chunkMessageIndex_)
    {
        std::stable_sort(
            entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
        Bytes list;
        for (const auto& [t, off] : entries) list.u64(t), list.u64(off);
        Bytes idx;
        idx.u16(channelId);
        idx.u32(uint32_t(list.b.size()));
        idx.raw(list.b.data(), list.b.size());
        Bytes r;
        r.record(kMessageIndex, idx);
        index.messageIndexOffsets[channelId] = offset_;
        writeBytes(r.b);
    }
    index.messageIndexLength = offset_ - indexesStart;
    chunkIndexes_.push_back(std::move(index));
    chunk_.clear();
    chunkMessageIndex_.clear();
}

void Writer::close()
{
    if (!file_) return;
    if (failed_)
    {
        // The write error was thrown when it happened: nothing more can be written.
        std::fclose(file_);
        file_ = nullptr;
        return;
    }
    flushChunk();

    Bytes dataEnd;
    dataEnd.u32(dataCrc_);
    Bytes rec;
    rec.record(kDataEnd, dataEnd);
    writeBytes(rec.b);

    // Summary: groups of records of one opcode, each group's place in a Summary Offset.
    const uint64_t summaryStart = offset_;
    inSummary_ = true;
    summaryCrc_ = 0;
    struct Group
    {
        uint8_t opcode;
        uint64_t start, length;
    };
    std::vector<Group> groups;
    const auto writeGroup = [&](uint8_t opcode, const std::vector<Bytes>& records)
    {
        if (records.empty()) return;
        const uint64_t start = offset_;
        for (const auto& content : records)
        {
            Bytes r;
            r.record(opcode, content);
            writeBytes(r.b);
        }
        groups.push_back({opcode, start, offset_ - start});
    };

    std::vector<Bytes> schemaRecords, channelRecords, chunkIndexRecords;
    for (const auto& s : schemas_)
    {
        Bytes c;
        c.u16(s.id);
        c.str(s.name);
        c.str(s.encoding);
        c.str(s.data);
        schemaRecords.push_back(std::move(c));
    }
    for (const auto& ch : channels_)
    {
        Bytes c;
        c.u16(ch.id);
        c.u16(ch.schemaId);
        c.str(ch.topic);
        c.str(ch.messageEncoding);
        c.map(ch.metadata);
        channelRecords.push_back(std::move(c));
    }
    Bytes stats;
    stats.u64(messageCount_);
    stats.u16(uint16_t(schemas_.size()));
    stats.u32(uint32_t(channels_.size()));
    stats.u32(0);  // attachments
    stats.u32(0);  // metadata records
    stats.u32(uint32_t(chunkIndexes_.size()));
    stats.u64(startTime_);
    stats.u64(endTime_);
    Bytes counts;
    for (const auto& ch : channels_) counts.u16(ch.id), counts.u64(ch.messageCount);
    stats.u32(uint32_t(counts.b.size()));
    stats.raw(counts.b.data(), counts.b.size());
    for (const auto& ci : chunkIndexes_)
    {
        Bytes c;
        c.u64(ci.startTime);
        c.u64(ci.endTime);
        c.u64(ci.chunkStart);
        c.u64(ci.chunkLength);
        Bytes offsets;
        for (const auto& [id, off] : ci.messageIndexOffsets) offsets.u16(id), offsets.u64(off);
        c.u32(uint32_t(offsets.b.size()));
        c.raw(offsets.b.data(), offsets.b.size());
        c.u64(ci.messageIndexLength);
        c.str(ci.compression);
        c.u64(ci.compressedSize);
        c.u64(ci.uncompressedSize);
        chunkIndexRecords.push_back(std::move(c));
    }
    writeGroup(kSchema, schemaRecords);
    writeGroup(kChannel, channelRecords);
    writeGroup(kStatistics, {stats});
    writeGroup(kChunkIndex, chunkIndexRecords);

    const uint64_t summaryOffsetStart = offset_;
    for (const auto& g : groups)
    {
        Bytes c;
        c.u8(g.opcode);
        c.u64(g.start);
        c.u64(g.length);
        Bytes r;
        r.record(kSummaryOffset, c);
        writeBytes(r.b);
    }

    // The footer's CRC covers the summary, the summary offsets and the footer up to itself.
    Bytes footerHead;
    footerHead.u8(kFooter);
    footerHead.u64(8 + 8 + 4);
    footerHead.u64(summaryStart);
    footerHead.u64(summaryOffsetStart);
    writeBytes(footerHead.b);
    Bytes tail;
    tail.u32(summaryCrc_);
    tail.raw(kMagic, sizeof(kMagic));
    writeBytes(tail.b);

    std::FILE* f = file_;
    file_ = nullptr;
    errno = 0;
    const bool flushed = std::fflush(f) == 0;
    const bool closed = std::fclose(f) == 0;
    if (!flushed || !closed) fail("writing MCAP file");
}

}  // namespace mrpt_wifi::mcap
