/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// MCAP files (https://mcap.dev/spec), written from the public specification: the container
// that ROS 2's rosbag2 records by default and that Foxglove opens directly. The file has
// chunked messages (zstd, lz4 or uncompressed), a message index per channel after each chunk,
// and a summary section (schemas, channels, statistics, chunk indexes) with summary offsets, so
// indexed readers seek and stream readers read it front to back.

#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace mrpt_wifi::mcap
{
enum class Compression
{
    None,
    Zstd,
    Lz4
};
/** "zstd", "lz4" or "none"; anything else throws std::invalid_argument naming the choices. */
Compression compressionFromString(const std::string& name);

struct WriterOptions
{
    Compression compression = Compression::Zstd;
    /** A chunk is closed when its uncompressed records reach this size. */
    size_t chunkSize = 1 << 20;
    std::string profile = "ros2";
};

/** Writes one MCAP file. Errors (the path not writable, the disk full) throw std::runtime_error
 *  naming the file. Messages may come in any order (the chunk indexes carry each chunk's time
 *  range), but viewers play a file best when each channel's messages are in log-time order. */
class Writer
{
public:
    explicit Writer(const std::string& path, WriterOptions options = {});
    /** Closes the file if close() was not called; errors are then only printed. */
    ~Writer();
    Writer(const Writer&) = delete;
    Writer& operator=(const Writer&) = delete;

    /** A schema (encoding "ros2msg" for ROS 2 .msg text); the same name, encoding and data
     *  twice returns the same id. */
    uint16_t addSchema(
        const std::string& name, const std::string& encoding, const std::string& data);
    uint16_t addChannel(
        uint16_t schemaId, const std::string& topic, const std::string& messageEncoding,
        const std::map<std::string, std::string>& metadata = {});
    /** A ROS 2 topic as rosbag2 writes it: schema `typeName` (e.g. "rf_msgs/msg/Wifi") in
     *  ros2msg, message encoding "cdr", metadata offered_qos_profiles (one reliable, volatile
     *  publisher). Returns the channel id. */
    uint16_t addRos2Channel(
        const std::string& topic, const std::string& typeName, const std::string& definition);

    /** One message; times in nanoseconds since the epoch. Each channel's sequence numbers count
     *  from 0. */
    void write(
        uint16_t channelId, uint64_t logTime_ns, uint64_t publishTime_ns, const uint8_t* data,
        size_t size);
    void write(uint16_t channelId, uint64_t logTime_ns, const std::vector<uint8_t>& data)
    {
        write(channelId, logTime_ns, logTime_ns, data.data(), data.size());
    }

    /** Flushes the last chunk, writes the summary, footer and closing magic. Throws naming the
     *  file when writing fails. After a write error (already thrown) it only closes the file. */
    void close();
    /** A write failed (the file is incomplete). */
    bool failed() const { return failed_; }

    const std::string& path() const { return path_; }
    uint64_t messageCount() const { return messageCount_; }

private:
    struct Schema
    {
        uint16_t id;
        std::string name, encoding, data;
    };
    struct Channel
    {
        uint16_t id, schemaId;
        std::string topic, messageEncoding;
        std::map<std::string, std::string> metadata;
        uint32_t nextSequence = 0;
        uint64_t messageCount = 0;
    };
    struct ChunkIndex
    {
        uint64_t startTime, endTime, chunkStart, chunkLength;
        std::map<uint16_t, uint64_t> messageIndexOffsets;
        uint64_t messageIndexLength;
        std::string compression;
        uint64_t compressedSize, uncompressedSize;
    };

    void writeBytes(const std::vector<uint8_t>& bytes);
    void flushChunk();
    [[noreturn]] void fail(const std::string& what) const;

    std::string path_;
    WriterOptions options_;
    std::FILE* file_ = nullptr;
    uint64_t offset_ = 0;      //!< bytes written to the file
    uint32_t dataCrc_ = 0;     //!< CRC32 of the data section so far
    bool inSummary_ = false;   //!< bytes now go to the summary CRC, not the data CRC
    bool failed_ = false;      //!< a write failed
    uint32_t summaryCrc_ = 0;  //!< CRC32 from the summary's start
    std::vector<Schema> schemas_;
    std::vector<Channel> channels_;
    std::vector<ChunkIndex> chunkIndexes_;
    // The open chunk: its uncompressed records and, per channel, (log time, offset in them).
    std::vector<uint8_t> chunk_;
    std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunkMessageIndex_;
    uint64_t chunkStart_ = 0, chunkEnd_ = 0;
    uint64_t messageCount_ = 0, startTime_ = 0, endTime_ = 0;
};

}  // namespace mrpt_wifi::mcap
