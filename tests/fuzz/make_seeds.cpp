// Writes seed corpora for the fuzz targets.
//   fuzz_make_seeds DIR                   fuzz_nexmon_assembler: valid frames of every header
//                                         variant and bandwidth, in the fuzzer's record format
//   fuzz_make_seeds DIR FORMAT DATA_DIR   fuzz_decoder_FORMAT: the sample files of
//                                         DATA_DIR/FORMAT plus one file per length check of
//                                         that decoder (a declared length that disagrees
//                                         with the bytes), so the fuzzer starts at each;
//                                         FORMAT rosmessages: rf_msgs/Wifi and Bearing bytes;
//                                         FORMAT rosbag2: fuzz_rosbag2's MCAP files (every
//                                         chunk compression, with and without CRCs and
//                                         summary), CDR messages and definitions;
//                                         FORMAT text, DATA_DIR share/: fuzz_text_inputs
#include <lz4frame.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <mrpt_wifi/sensor/Ros2Messages.h>
#include <mrpt_wifi/sensor/RosMessages.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;
namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

namespace
{
Bytes readFile(const fs::path& p)
{
    std::ifstream in(p, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + p.string());
    return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeFile(const fs::path& p, const Bytes& b)
{
    std::ofstream(p, std::ios::binary)
        .write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

int nexmonAssemblerSeeds(const fs::path& dir)
{
    int n = 0;
    for (auto variant :
         {NexmonHeaderVariant::Nexmon, NexmonHeaderVariant::NexmonLegacy,
          NexmonHeaderVariant::UbiLocate})
        for (unsigned bw : {20u, 40u, 80u})
        {
            std::ofstream f(dir / ("seed_" + std::to_string(n++)), std::ios::binary);
            f.put(char(uint8_t(variant) + 1));
            for (uint16_t seq = 0; seq < 2; ++seq)
                for (const auto& d : nexmon::encodeFrame(
                         *test::syntheticFrame(2, 2, bw, seq, "02:00:00:00:00:01", variant)))
                {
                    f.put(char(d.size() & 0xFF));
                    f.put(char(d.size() >> 8));
                    f.write(reinterpret_cast<const char*>(d.data()), std::streamsize(d.size()));
                }
        }
    return n;
}

/** Intel 5300 .dat: records of [2-byte BE length][code][payload]. */
std::map<std::string, Bytes> intelCases(const Bytes& sample)
{
    const size_t len0 = size_t(sample[0] << 8 | sample[1]);
    const Bytes first(sample.begin(), sample.begin() + long(2 + len0));
    const auto withLength = [](Bytes rec, size_t extra, uint8_t fill)
    {
        const size_t len = size_t(rec[0] << 8 | rec[1]) + extra;
        rec[0] = uint8_t(len >> 8), rec[1] = uint8_t(len & 0xFF);
        // The extra bytes between the 20-byte header and the CSI (the WSR Toolbox's place).
        rec.insert(rec.begin() + 2 + 21, extra, fill);
        return rec;
    };
    std::map<std::string, Bytes> c;
    c["wsr-variant"] = withLength(first, 18, 0x5A);
    c["record-longer-than-payload"] = withLength(first, 5, 0);
    Bytes field = first;
    field[2 + 1 + 16] ^= 0x01;  // the payload-length field no longer matches Nrx·Ntx
    c["payload-field-mismatch"] = field;
    Bytes two = first;
    two.insert(two.end(), first.begin(), first.end() - 40);  // second record cut
    c["truncated-tail"] = two;
    return c;
}

/** Atheros CSI Tool: records of [2-byte LE length][25-byte status][CSI][payload]. */
std::map<std::string, Bytes> atherosCases(const Bytes& sample)
{
    const size_t len0 = size_t(sample[0] | sample[1] << 8);
    const Bytes first(sample.begin(), sample.begin() + long(2 + len0));
    std::map<std::string, Bytes> c;
    Bytes csiLen = first;
    csiLen[2 + 8] ^= 0x02;  // csi_len vs the record length
    c["sizes-do-not-add-up"] = csiLen;
    Bytes tones = first;
    tones[2 + 17] = 1, tones[2 + 18] = 1;  // 1x1 where csi_len holds more
    c["csi-len-vs-antennas"] = tones;
    Bytes two = first;
    two.insert(two.end(), first.begin(), first.end() - 100);
    c["truncated-tail"] = two;
    return c;
}

/** esp-csi / ESP32-CSI-Tool lines. */
std::map<std::string, Bytes> esp32Cases(const Bytes& sample, const Bytes& csiTool)
{
    const std::string text(sample.begin(), sample.end());
    const std::string line = text.substr(0, text.find('\n') + 1);
    std::map<std::string, Bytes> c;
    const auto put = [&](const std::string& name, const std::string& s)
    { c[name] = Bytes(s.begin(), s.end()); };
    // len says more than the bracket holds (not exactly the L-LTF).
    const size_t close = line.rfind(']');
    put("len-vs-values", line.substr(0, close - 8) + line.substr(close));
    put("cut-last-line", line + line.substr(0, line.size() / 2));
    put("csi-tool-short-rows", std::string(csiTool.begin(), csiTool.end()));
    return c;
}

Bytes serialized(const mrpt::serialization::CSerializable& object)
{
    mrpt::io::CMemoryStream stream;
    mrpt::serialization::archiveFrom(stream) << object;
    const auto* p = static_cast<const uint8_t*>(stream.getRawBufferData());
    return Bytes(p, p + stream.getTotalBytesCount());
}

/** Nexmon captures: a pcap whose last record is cut, one datagram of the wrong size; stored
 * frames (the rawlog path): valid, cut short, and an object of another MRPT class. */
std::map<std::string, Bytes> nexmonCases(const fs::path& tmp)
{
    std::map<std::string, Bytes> c;
    const auto frame = test::syntheticFrame(2, 2, 80, 1);
    {
        PcapWriter w((tmp / "full.pcap").string());
        for (const auto& d : nexmon::encodeFrame(*frame))
            w.writeUdp(d.data(), d.size(), mrpt::Clock::fromDouble(1.0));
        auto bad = nexmon::encodeFrame(*frame).front();
        bad.resize(bad.size() - 4);  // length disagrees with the bandwidth's NFFT
        w.writeUdp(bad.data(), bad.size(), mrpt::Clock::fromDouble(1.1));
    }
    Bytes full = readFile(tmp / "full.pcap");
    c["wrong-size-datagram"] = full;
    full.resize(full.size() - 30);
    c["truncated-tail"] = full;
    fs::remove(tmp / "full.pcap");
    Bytes stored = serialized(*frame);
    c["stored-frame"] = stored;
    stored.resize(stored.size() / 2);
    c["stored-frame-cut"] = stored;
    c["stored-foreign-class"] = serialized(mrpt::obs::CObservationOdometry());
    return c;
}
/** rf_msgs/Wifi and rf_msgs/Bearing bytes: valid ones, and each declared size disagreeing. */
std::map<std::string, Bytes> rosMessageCases()
{
    std::map<std::string, Bytes> c;
    const auto wifi = ros1::fromObservation(*test::syntheticFrame(2, 2, 20, 3), "rx");
    c["wifi-valid"] = ros1::serialize(wifi);
    auto shortCsi = wifi;
    shortCsi.csiImag.resize(shortCsi.csiImag.size() - 1);
    c["wifi-csi-shorter-than-n_sub-rows-cols"] = ros1::serialize(shortCsi);
    auto nsub = wifi;
    nsub.nSub = 128;  // not 20 MHz's FFT size
    c["wifi-n_sub-vs-bw"] = ros1::serialize(nsub);
    Bytes cut = ros1::serialize(wifi);
    cut.resize(cut.size() / 2);
    c["wifi-cut"] = cut;
    ros1::BearingMessage b;
    b.txmac = {2, 0, 0, 0, 10, 1};
    b.rssi = {-40};
    b.aoa = {0.5};
    c["bearing-valid"] = ros1::serialize(b);
    return c;
}

/** A minimal MCAP encoder (https://mcap.dev/spec) for fuzz_rosbag2's seeds, independent of the
 *  reader under test: one schema and channel for rf_msgs/msg/Wifi, one for std_msgs/msg/String,
 *  all records in one chunk (compression "zstd", "lz4", "none") or, with "unchunked", directly
 *  in the data section. */
Bytes mcapSeed(const std::string& compression, bool withCrcs, bool withSummary)
{
    const auto le = [](Bytes& b, uint64_t v, int n)
    {
        for (int i = 0; i < n; ++i) b.push_back(uint8_t(v >> (8 * i)));
    };
    const auto str = [&](Bytes& b, const std::string& s)
    {
        le(b, s.size(), 4);
        b.insert(b.end(), s.begin(), s.end());
    };
    const auto record = [&](Bytes& out, uint8_t op, const Bytes& content)
    {
        out.push_back(op);
        le(out, content.size(), 8);
        out.insert(out.end(), content.begin(), content.end());
    };
    const auto crc = [&](const Bytes& b)
    { return withCrcs ? uint32_t(crc32(0, b.data(), uInt(b.size()))) : 0u; };
    Bytes records;
    const auto schema = [&](uint16_t id, const std::string& name, const std::string& text)
    {
        Bytes c;
        le(c, id, 2), str(c, name), str(c, "ros2msg"), str(c, text);
        record(records, 0x03, c);
    };
    const auto channel = [&](uint16_t id, uint16_t schemaId, const std::string& topic)
    {
        Bytes c, metadata;
        le(c, id, 2), le(c, schemaId, 2), str(c, topic), str(c, "cdr");
        str(metadata, "offered_qos_profiles"), str(metadata, "");
        le(c, metadata.size(), 4);
        c.insert(c.end(), metadata.begin(), metadata.end());
        record(records, 0x04, c);
    };
    const auto message = [&](uint16_t channelId, uint64_t t, const Bytes& data)
    {
        Bytes c;
        le(c, channelId, 2), le(c, 0, 4), le(c, t, 8), le(c, t, 8);
        c.insert(c.end(), data.begin(), data.end());
        record(records, 0x05, c);
    };
    schema(1, ros2::wifiType().name, ros2::wifiType().definition);
    schema(2, "std_msgs/msg/String", "string data\n");
    channel(1, 1, "/csi");
    channel(2, 2, "/chatter");
    const uint64_t t0 = 1700000000ull * 1000000000ull;
    for (unsigned i = 0; i < 2; ++i)
    {
        auto w = ros1::fromObservation(
            *test::syntheticFrame(1, 2, 20, uint16_t(i)), "rx" + std::to_string(i));
        message(1, t0 + i, ros2::serializeCdr(w));
    }
    message(2, t0 + 5, Bytes{0, 1, 0, 0, 3, 0, 0, 0, 'h', 'i', 0});
    Bytes packed = records;
    if (compression == "zstd")
    {
        packed.resize(ZSTD_compressBound(records.size()));
        packed.resize(
            ZSTD_compress(packed.data(), packed.size(), records.data(), records.size(), 3));
    }
    else if (compression == "lz4")
    {
        packed.resize(LZ4F_compressFrameBound(records.size(), nullptr));
        packed.resize(LZ4F_compressFrame(
            packed.data(), packed.size(), records.data(), records.size(), nullptr));
    }
    Bytes file = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
    Bytes header;
    str(header, "ros2"), str(header, "fuzz_make_seeds");
    record(file, 0x01, header);
    if (compression == "unchunked") file.insert(file.end(), records.begin(), records.end());
    Bytes chunk;
    le(chunk, t0, 8), le(chunk, t0 + 5, 8), le(chunk, records.size(), 8),
        le(chunk, crc(records), 4);
    str(chunk, compression == "none" ? "" : compression);
    le(chunk, packed.size(), 8);
    chunk.insert(chunk.end(), packed.begin(), packed.end());
    if (compression != "unchunked") record(file, 0x06, chunk);
    Bytes dataEnd;
    le(dataEnd, crc(file), 4);
    record(file, 0x0F, dataEnd);
    const uint64_t summaryStart = file.size();
    if (withSummary)
    {
        Bytes stats;  // Statistics: counts only
        le(stats, 3, 8), le(stats, 2, 2), le(stats, 2, 4), le(stats, 0, 4), le(stats, 0, 4);
        le(stats, 1, 4), le(stats, t0, 8), le(stats, t0 + 5, 8), le(stats, 0, 4);
        record(file, 0x0B, stats);
    }
    Bytes footer;
    le(footer, withSummary ? summaryStart : 0, 8), le(footer, 0, 8);
    Bytes covered(file.begin() + long(summaryStart), file.end());
    covered.push_back(0x02);
    le(covered, 20, 8);
    covered.insert(covered.end(), footer.begin(), footer.end());
    le(footer, withSummary ? crc(covered) : 0, 4);
    record(file, 0x02, footer);
    file.insert(file.end(), {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'});
    return file;
}

/** fuzz_rosbag2: the first byte picks the input kind (0 MCAP, 1 CDR, 2 definition text). */
std::map<std::string, Bytes> rosbag2Cases()
{
    std::map<std::string, Bytes> c;
    const auto prefixed = [](uint8_t kind, Bytes b)
    {
        b.insert(b.begin(), kind);
        return b;
    };
    for (const std::string compression : {"zstd", "lz4", "none"})
        c["mcap-" + compression] = prefixed(0, mcapSeed(compression, true, true));
    // Without CRCs a mutation inside the chunk reaches the record parser.
    c["mcap-zstd-no-crc-no-summary"] = prefixed(0, mcapSeed("zstd", false, false));
    c["mcap-none-no-crc-no-summary"] = prefixed(0, mcapSeed("none", false, false));
    c["mcap-unchunked"] = prefixed(0, mcapSeed("unchunked", true, true));
    const auto wifi = ros1::fromObservation(*test::syntheticFrame(2, 2, 20, 3), "rx");
    c["cdr-wifi"] = prefixed(1, ros2::serializeCdr(wifi));
    auto shortCsi = wifi;
    shortCsi.csiImag.pop_back();
    c["cdr-wifi-csi-shorter-than-n_sub-rows-cols"] = prefixed(1, ros2::serializeCdr(shortCsi));
    ros1::BearingMessage b;
    b.txmac = {2, 0, 0, 0, 10, 1};
    b.rssi = {-40};
    b.aoa = {0.5};
    c["cdr-bearing"] = prefixed(1, ros2::serializeCdr(b));
    const std::string& d = ros2::wifiType().definition;
    c["definition-wifi"] = prefixed(2, Bytes(d.begin(), d.end()));
    return c;
}

/** fuzz_text_inputs: the first byte picks the reader (0 bearings CSV, 1 TUM, 2 WSR-style CSV
 *  trajectory, 3 AP map YAML, 4 .ini). The project's shipped YAML and .ini files from
 *  SHARE_DIR, and small valid CSV and trajectories in every column layout the readers take. */
std::map<std::string, Bytes> textCases(const fs::path& share)
{
    std::map<std::string, Bytes> c;
    const auto prefixed = [](uint8_t reader, const std::string& text)
    {
        Bytes b{reader};
        b.insert(b.end(), text.begin(), text.end());
        return b;
    };
    const auto prefixedFile = [&](uint8_t reader, const fs::path& p)
    {
        Bytes b{reader};
        const Bytes f = readFile(p);
        b.insert(b.end(), f.begin(), f.end());
        return b;
    };
    for (const auto& e : fs::recursive_directory_iterator(share))
    {
        if (!e.is_regular_file() || e.file_size() > 200000) continue;
        const auto ext = e.path().extension();
        const std::string name = fs::relative(e.path(), share).string();
        if (ext == ".ini") c["ini-" + name] = prefixedFile(4, e.path());
        if (ext == ".yaml" && name.find("aps") != std::string::npos)
            c["yaml-" + name] = prefixedFile(3, e.path());
        if (name == "calibration/transmitters.example.yaml")
            c["yaml-" + name] = prefixedFile(3, e.path());
    }
    c["csv-all-columns"] = prefixed(
        0,
        "# comment\n"
        "timestamp,transmitter,aoa_deg,aoa_std_deg,aoa_mirror_deg,aod_deg,aod_std_deg,"
        "aod_mirror_deg,has_aoa,has_aod,aoa_ambiguous,aod_ambiguous,aoa_alt_deg,aoa_alt_weight,"
        "aoa_direction_std_deg\n"
        "1700000000.10,02:00:00:00:0a:01,23.5,4.0,156.5,-12.0,5.0,,1,1,1,0,-40,0.3,3\n"
        "1700000000.20,ap-b,,,,-12.0,5.0,192,0,1,0,1,,,\n");
    c["csv-aod-several-per-timestamp"] = prefixed(
        0,
        "timestamp,transmitter,aod_deg,aod_std_deg\n"
        "1700000000.5,ap-a,10,5\n1700000000.5,ap-a,12,5\n1700000000.5,ap-b,-30,5\n");
    c["csv-reordered-columns"] =
        prefixed(0, "aoa_deg,transmitter,timestamp\n10,02:00:00:00:0a:02,1700000000\n");
    c["tum"] = prefixed(
        1,
        "# t x y z qx qy qz qw\n"
        "1700000000.0 1 2 0 0 0 0 1\n1700000000.1 1.05 2 0 0 0 0.0499792 0.9987503\n");
    c["wsr-csv"] = prefixed(
        2,
        "1700000000,0,1,2,0,0,0,0,1\n1700000000,100000000,1.05,2,0,0,0,0,1\n1700000000.5,0,1.1,2,0."
        "3\n");
    // Inputs the fuzzer found leaking (fixed): a bad likelihoodOpts value thrown while MRPT's
    // loader holds the map definition; an AP map that is not UTF-8.
    c["ini-bad-likelihood-value"] = prefixed(
        4,
        "[MetricMap]\nwifiBearingMap_count = 1\n[MetricMap_wifiBearingMap_00_likelihoodOpts]\n"
        "outlier_prob = 2\n");
    c["yaml-not-utf8"] =
        prefixed(3, "transmitters:\n  - {name: caf\xe9, mac: '02:00:00:00:0a:01'}\n");
    return c;
}
}  // namespace

int main(int argc, char** argv)
{
    if (argc != 2 && argc != 4)
    {
        std::cerr << "usage: fuzz_make_seeds DIR [FORMAT DATA_DIR]\n";
        return 1;
    }
    const fs::path dir = argv[1];
    fs::create_directories(dir);
    if (argc == 2)
    {
        std::cout << "wrote " << nexmonAssemblerSeeds(dir) << " seeds to " << dir.string() << "\n";
        return 0;
    }
    const std::string format = argv[2];
    const fs::path data = argv[3];
    std::map<std::string, Bytes> cases;
    const auto firstFile = [&](const std::string& sub, const std::string& ext)
    {
        for (const auto& e : fs::directory_iterator(data / sub))
            if (e.path().extension() == ext) return readFile(e.path());
        throw std::runtime_error("no " + ext + " sample in " + (data / sub).string());
    };
    if (format == "intel5300")
        cases = intelCases(firstFile("intel5300", ".dat"));
    else if (format == "atheros")
        cases = atherosCases(firstFile("atheros", ".dat"));
    else if (format == "esp32")
        cases = esp32Cases(
            readFile(data / "esp32" / "csi_data.csv"),
            readFile(data / "esp32-csi-tool" / "example_data.first20.csv"));
    else if (format == "nexmon")
        cases = nexmonCases(dir);
    else if (format == "rosmessages")
        cases = rosMessageCases();
    else if (format == "rosbag2")
        cases = rosbag2Cases();
    else if (format == "text")
        cases = textCases(data);
    else
    {
        std::cerr << "fuzz_make_seeds: unknown format '" << format << "'\n";
        return 1;
    }
    for (const auto& [name, bytes] : cases)
    {
        std::string file =
            (format == "rosmessages" || format == "rosbag2" || format == "text" ? ""
                                                                                : "length-check-") +
            name;
        std::replace(file.begin(), file.end(), '/', '_');
        writeFile(dir / file, bytes);
    }
    std::cout << "wrote " << cases.size() << " length-check seeds for " << format << " to "
              << dir.string() << "\n";
    return 0;
}
