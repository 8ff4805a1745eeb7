/* Decoders of every CSI source against the public sample captures in tests/data and the values
 * each format's own reference tool produced for them (see tests/data/<format>/README.md). */
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/AtherosCsiFormat.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/Esp32CsiFormat.h>
#include <mrpt_wifi/sensor/Intel5300Format.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <mrpt_wifi/sensor/PcapIO.h>

#include <complex>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "TestSupport.h"

using namespace mrpt_wifi;
using Complex = std::complex<double>;

namespace
{
std::string data(const std::string& rel)
{
    return test::sourceDir() + "/tests/data/" + rel;
}

/** Rows of a CSV with a header line, as numbers. */
std::vector<std::vector<double>> readCsv(const std::string& path)
{
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << path;
    std::string line;
    std::getline(in, line);  // header
    std::vector<std::vector<double>> rows;
    while (std::getline(in, line))
    {
        std::vector<double> row;
        std::stringstream ss(line);
        std::string cell;
        while (std::getline(ss, cell, ',')) row.push_back(std::stod(cell));
        rows.push_back(std::move(row));
    }
    return rows;
}

/** |<a, b>| / (|a| |b|): 1 when b is a positive real multiple of a... up to a common phase;
 * the real part of the normalised inner product also demands the same phase. */
double correlation(const std::vector<Complex>& a, const std::vector<Complex>& b)
{
    Complex ab = 0;
    double aa = 0, bb = 0;
    for (size_t i = 0; i < a.size(); ++i)
    {
        ab += std::conj(a[i]) * b[i];
        aa += std::norm(a[i]);
        bb += std::norm(b[i]);
    }
    return ab.real() / std::sqrt(aa * bb);
}

std::vector<CObservationWiFiCSI::Ptr> decodeAll(
    const std::string& path, const std::string& format = "auto", CsiDecodeSummary* s = nullptr,
    CsiDecodeOptions options = {})
{
    std::vector<CObservationWiFiCSI::Ptr> frames;
    decodeCsiFile(
        path, format, options, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); }, {}, s);
    return frames;
}

// --------------------------------------------------------------------------- Nexmon
struct NexmonSample
{
    const char* file;
    nexmon::Chip chip;
};

class NexmonReference : public ::testing::TestWithParam<NexmonSample>
{
};

TEST_P(NexmonReference, EveryDatagramMatchesNexmonCsiReader)
{
    const auto& s = GetParam();
    const std::string pcap = data(std::string("nexmon/") + s.file + ".pcap");
    const auto ref = readCsv(data(std::string("nexmon/") + s.file + ".reference.csv"));
    std::map<int, std::vector<Complex>> refByDatagram;
    for (const auto& r : ref) refByDatagram[int(r[0])].emplace_back(r[2], r[3]);

    PcapReader reader(pcap, nexmon::kDefaultUdpPort);
    PcapUdpDatagram d;
    int k = 0;
    while (reader.next(d))
    {
        nexmon::DatagramHeader h;
        nexmon::RejectReason why{};
        ASSERT_TRUE(
            nexmon::parseHeader(d.payload, d.payloadLength, nexmon::FormatHint::Auto, h, why))
            << toString(why);
        EXPECT_EQ(h.chip, s.chip);
        const unsigned n = h.nfft();
        std::vector<std::complex<float>> bins(n);
        nexmon::decodeWords(h.chip, d.payload + nexmon::csiOffset(), n, bins.data());
        // The reference is in raw (FFT) order: raw index i is bin (i + N/2) mod N.
        std::vector<Complex> ours(n);
        for (unsigned i = 0; i < n; ++i) ours[i] = bins[(i + n / 2) % n];
        const auto& theirs = refByDatagram.at(k);
        ASSERT_EQ(theirs.size(), n);
        EXPECT_GE(correlation(ours, theirs), 0.9999) << s.file << " datagram " << k;
        ++k;
    }
    EXPECT_EQ(size_t(k), refByDatagram.size());
}

INSTANTIATE_TEST_SUITE_P(
    Chips, NexmonReference,
    ::testing::Values(
        NexmonSample{"bcm4339-80mhz", nexmon::Chip::BCM4339},
        NexmonSample{"bcm43455c0-80mhz", nexmon::Chip::BCM43455c0},
        NexmonSample{"bcm4358-80mhz", nexmon::Chip::BCM4358}),
    [](const auto& sample)
    {
        std::string n = sample.param.file;
        std::replace(n.begin(), n.end(), '-', '_');
        return n;
    });

TEST(NexmonChips, Int16ChipsDecodeExactlyTheReferenceIntegers)
{
    // typecast(int16) is exact: not only correlated, equal.
    for (const char* f : {"bcm4339-80mhz", "bcm43455c0-80mhz"})
    {
        const auto ref = readCsv(data(std::string("nexmon/") + f + ".reference.csv"));
        PcapReader reader(data(std::string("nexmon/") + f + ".pcap"), nexmon::kDefaultUdpPort);
        PcapUdpDatagram d;
        size_t row = 0;
        while (reader.next(d))
        {
            nexmon::DatagramHeader h;
            nexmon::RejectReason why{};
            ASSERT_TRUE(nexmon::parseHeader(d.payload, d.payloadLength, {}, h, why));
            std::vector<std::complex<float>> bins(h.nfft());
            nexmon::decodeWords(h.chip, d.payload + nexmon::csiOffset(), h.nfft(), bins.data());
            for (unsigned i = 0; i < h.nfft(); ++i, ++row)
            {
                const auto v = bins[(i + h.nfft() / 2) % h.nfft()];
                ASSERT_EQ(v.real(), ref[row][2]) << f << " row " << row;
                ASSERT_EQ(v.imag(), ref[row][3]) << f << " row " << row;
            }
        }
        EXPECT_EQ(row, ref.size());
    }
}

TEST(NexmonChips, FramesCarryTheChipShapeAndSource)
{
    {
        CsiDecodeSummary s;
        const auto frames = decodeAll(data("nexmon/bcm43455c0-80mhz.pcap"), "auto", &s);
        EXPECT_EQ(s.format, "nexmon");
        // The Pi reports sequence number 0 for every frame: each datagram is its own 1x1 frame.
        ASSERT_EQ(frames.size(), 8u);
        for (const auto& f : frames)
        {
            EXPECT_EQ(f->source, "bcm43455c0");
            EXPECT_EQ(f->nRx, 1);
            EXPECT_EQ(f->nTx, 1);
            EXPECT_TRUE(f->isComplete());
            EXPECT_EQ(f->chanspec.bandwidthMHz, 80u);
            EXPECT_LT(f->rssi_dBm, 0);  // the current header's RSSI byte
        }
        EXPECT_EQ(frames.front()->rssi_dBm, -58);  // 0xc6 in the first datagram
    }
    {
        // nexmon_csi's example: one frame of the BCM4358, 2 cores x 2 streams.
        const auto frames = decodeAll(data("nexmon/bcm4358-80mhz.pcap"));
        ASSERT_EQ(frames.size(), 1u);
        EXPECT_EQ(frames[0]->source, "bcm4358");
        EXPECT_EQ(frames[0]->nRx, 2);
        EXPECT_EQ(frames[0]->nTx, 2);
        EXPECT_TRUE(frames[0]->isComplete());
    }
}

TEST(NexmonChips, UnknownChipWordIsRejectedNamingTheReason)
{
    std::vector<uint8_t> d(nexmon::datagramSize(NexmonHeaderVariant::Nexmon, 64), 0);
    d[0] = d[1] = 0x11;
    const uint16_t cs = Chanspec::make(36, 20).raw;
    d[14] = uint8_t(cs);
    d[15] = uint8_t(cs >> 8);
    d[16] = 0x42;  // no nexmon_csi chip
    nexmon::DatagramHeader h;
    nexmon::RejectReason why{};
    EXPECT_FALSE(nexmon::parseHeader(d.data(), d.size(), {}, h, why));
    EXPECT_EQ(why, nexmon::RejectReason::UnknownChip);
    // A core the chip doesn't have (the Pi has one).
    d[16] = 0x65;
    d[12] = 0x01;  // core 1
    EXPECT_FALSE(nexmon::parseHeader(d.data(), d.size(), {}, h, why));
    EXPECT_EQ(why, nexmon::RejectReason::BadCoreStream);
}

TEST(NexmonChips, Bcm4358WordLayout)
{
    // Real −3·2^−2, imaginary +5·2^−2: exponent −2 (5 bits), imag mantissa at bit 5, its sign at
    // bit 13, real mantissa at bit 14, its sign at bit 22.
    const uint32_t w = (uint32_t(-2) & 0x1F) | (5u << 5) | (3u << 14) | (1u << 22);
    const auto v = nexmon::unpackWord4358(w);
    EXPECT_FLOAT_EQ(v.real(), -0.75f);
    EXPECT_FLOAT_EQ(v.imag(), 1.25f);
}

// --------------------------------------------------------------------------- Intel 5300
TEST(Intel5300, MatchesReadBfFileAndGetScaledCsi)
{
    CsiDecodeSummary s;
    const auto frames = decodeAll(data("intel5300/log.all_csi.6.7.6.dat"), "auto", &s);
    EXPECT_EQ(s.format, "intel5300");
    const auto ref = readCsv(data("intel5300/log.all_csi.6.7.6.reference.csv"));
    ASSERT_EQ(frames.size(), 29u);
    std::map<int, std::vector<Complex>> raw, scaled;
    for (const auto& r : ref)
    {
        raw[int(r[0])].emplace_back(r[4], r[5]);
        scaled[int(r[0])].emplace_back(r[6], r[7]);
    }
    std::set<int> shapes;
    for (size_t i = 0; i < frames.size(); ++i)
    {
        const auto& f = *frames[i];
        EXPECT_EQ(f.source, "iwl5300");
        ASSERT_EQ(f.nRx, 3);
        shapes.insert(f.nTx);
        ASSERT_EQ(f.dataSubcarriers().size(), 30u);
        const auto sc = f.scaledCsi();
        ASSERT_EQ(sc.size(), f.csi.size());
        std::vector<Complex> ours, oursScaled;
        // Reference rows: tx, rx, subcarrier (innermost).
        for (unsigned tx = 0; tx < f.nTx; ++tx)
            for (unsigned rx = 0; rx < f.nRx; ++rx)
                for (int k : f.dataSubcarriers())
                {
                    const size_t idx =
                        (size_t(tx) * f.nRx + rx) * f.nfft() + subcarrierToBin(k, f.nfft());
                    ours.emplace_back(f.csi[idx]);
                    oursScaled.emplace_back(sc[idx]);
                }
        ASSERT_EQ(ours.size(), raw.at(int(i)).size());
        EXPECT_GE(correlation(ours, raw.at(int(i))), 0.9999) << "record " << i;
        for (size_t j = 0; j < ours.size(); ++j)
        {
            EXPECT_EQ(ours[j], raw.at(int(i))[j]) << "record " << i << " value " << j;
            EXPECT_NEAR(
                std::abs(oursScaled[j] - scaled.at(int(i))[j]), 0.0,
                1e-5 * (1 + std::abs(scaled.at(int(i))[j])));
        }
        EXPECT_GE(correlation(oursScaled, scaled.at(int(i))), 0.9999);
        EXPECT_EQ(f.antennaRssi_dB.size(), 3u);
        EXPECT_FALSE(std::isnan(f.agc_dB));
    }
    // The sample holds 3 x 1, 3 x 2 and 3 x 3 records.
    EXPECT_EQ(shapes, (std::set<int>{1, 2, 3}));
}

TEST(Intel5300, SubcarrierGroupingFollows80211n)
{
    const auto& k20 = intel5300::groupedSubcarriers(false);
    EXPECT_EQ(k20.front(), -28);
    EXPECT_EQ(k20.back(), 28);
    const auto& k40 = intel5300::groupedSubcarriers(true);
    EXPECT_EQ(k40.front(), -58);
    EXPECT_EQ(k40[15], 2);
}

// --------------------------------------------------------------------------- ESP32
TEST(Esp32, MatchesTheIntegersEspIdfWrote)
{
    CsiDecodeSummary s;
    CsiDecodeOptions legacy;
    legacy.esp32LegacyLtf = true;  // the L-LTF, though the lines also carry HT-LTFs
    const auto frames = decodeAll(data("esp32/csi_data.csv"), "auto", &s, legacy);
    EXPECT_EQ(s.format, "esp32");
    const auto ref = readCsv(data("esp32/csi_data.reference.csv"));
    ASSERT_EQ(frames.size(), 8u);
    ASSERT_EQ(ref.size(), 8u * 64u);
    for (size_t i = 0; i < frames.size(); ++i)
    {
        const auto& f = *frames[i];
        EXPECT_EQ(f.source, "esp32");
        EXPECT_EQ(f.nRx, 1);
        EXPECT_EQ(f.chanspec.centerChannel, 1);
        EXPECT_EQ(f.transmitter.asString(), "70:3a:73:0c:6c:fb");
        EXPECT_EQ(f.noiseFloor_dBm, -91.f);
        std::vector<Complex> ours, theirs;
        for (unsigned raw = 0; raw < 64; ++raw)
        {
            const auto& r = ref[i * 64 + raw];
            const Complex expected(r[3], r[2]);  // [imag, real] in the buffer
            const Complex got = f.at(0, 0, (raw + 32) % 64);
            EXPECT_EQ(got, expected) << "line " << i << " subcarrier " << raw;
            const int k = raw < 32 ? int(raw) : int(raw) - 64;
            if (k != 0 && std::abs(k) <= 26)
            {
                ours.push_back(got);
                theirs.push_back(expected);
            }
        }
        EXPECT_GE(correlation(ours, theirs), 0.9999);
        // first_word_invalid = 1: the buffer's first 4 bytes (k = 0 and k = +1) are no CSI.
        EXPECT_EQ(f.dataSubcarriers().size(), 51u);
        EXPECT_EQ(f.maskedBins, std::vector<uint16_t>{33});
    }
}

// ESP32-CSI-Tool (issue 20.1): a 26-column header, then rows whose len says 384 while the
// bracket holds 128 (the L-LTF). Every row is read, value for value as awk reads the bytes, and
// the assumptions are said once.
TEST(Esp32, CsiToolRowsShorterThanTheirLenAreReadAsTheLltf)
{
    CsiDecodeSummary s;
    const auto frames = decodeAll(data("esp32-csi-tool/example_data.first20.csv"), "auto", &s);
    EXPECT_EQ(s.format, "esp32");
    EXPECT_EQ(s.rejectedRecords(), 0u) << s.asString();
    EXPECT_EQ(s.skipped, 1u);  // the header row
    ASSERT_EQ(frames.size(), 20u) << s.asString();
    size_t notesAboutLen = 0, notesAboutFirstWord = 0;
    for (const auto& n : s.notes)
    {
        notesAboutLen += n.find("len announces 384 values hold 128") != std::string::npos;
        notesAboutFirstWord += n.find("first_word_invalid") != std::string::npos;
    }
    EXPECT_EQ(notesAboutLen, 1u) << s.asString();
    EXPECT_EQ(notesAboutFirstWord, 1u) << s.asString();

    std::ifstream meta(data("esp32-csi-tool/example_data.first20.meta.reference.csv"));
    std::string line;
    std::getline(meta, line);
    const auto values = readCsv(data("esp32-csi-tool/example_data.first20.reference.csv"));
    ASSERT_EQ(values.size(), 20u * 64u);
    for (size_t i = 0; i < frames.size(); ++i)
    {
        ASSERT_TRUE(std::getline(meta, line));
        std::vector<std::string> c;
        std::stringstream ss(line);
        for (std::string x; std::getline(ss, x, ',');) c.push_back(x);
        ASSERT_EQ(c.size(), 7u);
        const auto& f = *frames[i];
        EXPECT_EQ(f.transmitter.asString(), MacAddress::fromString(c[1]).asString());
        EXPECT_EQ(f.rssi_dBm, std::stoi(c[2]));
        EXPECT_EQ(f.noiseFloor_dBm, std::stof(c[3]));
        EXPECT_EQ(f.chanspec.centerChannel, std::stoul(c[4]));
        EXPECT_EQ(f.chanspec.bandwidthMHz, 20u);
        EXPECT_NEAR(mrpt::Clock::toDouble(f.timestamp), std::stod(c[5]) * 1e-6, 1e-6);
        EXPECT_EQ(f.nTx, 1);
        EXPECT_EQ(f.nRx, 1);
        // Buffer entry e is subcarrier k = e (0..31) or e - 64 (32..63): ESP-IDF's FFT order.
        for (unsigned e = 0; e < 64; ++e)
        {
            const auto& r = values[i * 64 + e];
            ASSERT_EQ(size_t(r[0]), i);
            const int k = e < 32 ? int(e) : int(e) - 64;
            EXPECT_EQ(
                f.at(0, 0, unsigned(k + 32)),
                CObservationWiFiCSI::Complex(float(r[3]), float(r[2])))
                << "row " << i << " entry " << e;
        }
        // The first four bytes (k = 0, +1) are masked; the L-LTF's other 51 are measured.
        EXPECT_EQ(f.maskedBins, std::vector<uint16_t>{33});
        EXPECT_EQ(f.dataSubcarriers().size(), 51u);
    }
}

// A row whose bracket is neither its len nor exactly the L-LTF is still refused, alone.
TEST(Esp32, CsiToolRowWithAnotherShortBufferIsSkipped)
{
    test::TempDir tmp;
    std::string text = test::readFile(data("esp32-csi-tool/example_data.first20.csv"));
    // Row 2 (line 3) loses its last two values: 126 held, 384 announced.
    const size_t row2 = text.find('\n', text.find('\n') + 1) + 1;
    const size_t close = text.find(']', row2);
    const size_t cut = text.rfind(' ', text.rfind(' ', close - 2) - 1);
    text.erase(cut, close - cut - 1);
    std::ofstream(tmp.file("short.csv")) << text;
    CsiDecodeSummary s;
    const auto frames = decodeAll(tmp.file("short.csv"), "auto", &s);
    EXPECT_EQ(frames.size(), 19u);
    ASSERT_EQ(s.rejected.size(), 1u) << s.asString();
    EXPECT_EQ(s.rejected[0].reason, "len disagrees with the values in the buffer");
    EXPECT_EQ(
        s.rejected[0].firstWhere.rfind("line 3, len says 384 values, the buffer has 126", 0), 0u)
        << s.rejected[0].firstWhere;
}

// The sample's lines are HT20 with STBC (sig_mode 1, cwb 0, stbc 1, no secondary channel, 384
// values): L-LTF, HT-LTF and STBC-HT-LTF, 64 subcarriers each in FFT order (ESP-IDF's table).
// By default a frame holds the HT-LTF as stream 0 and the STBC-HT-LTF as stream 1, on the
// HT20 subcarriers ±1..±28, exactly the integers ESP-IDF wrote.
TEST(Esp32, HtLtfAndStbcStreamFromEspIdfTable)
{
    CsiDecodeSummary s;
    const auto frames = decodeAll(data("esp32/csi_data.csv"), "auto", &s);
    const auto ref = readCsv(data("esp32/csi_data.htltf.reference.csv"));
    ASSERT_EQ(frames.size(), 8u);
    ASSERT_EQ(ref.size(), 8u * 2u * 64u);
    EXPECT_NE(s.details.find("8 frames from the HT-LTF (8 with STBC"), std::string::npos)
        << s.details;
    std::vector<int> ht20;
    for (int k = -28; k <= 28; ++k)
        if (k) ht20.push_back(k);
    for (size_t i = 0; i < frames.size(); ++i)
    {
        const auto& f = *frames[i];
        ASSERT_EQ(f.nTx, 2);
        ASSERT_EQ(f.nRx, 1);
        EXPECT_TRUE(f.isComplete());
        EXPECT_EQ(f.chanspec.asString(), "1/20");
        EXPECT_EQ(f.dataSubcarriers(), ht20);
        EXPECT_TRUE(f.maskedBins.empty());  // the invalid first word is in the L-LTF
        for (unsigned field = 0; field < 2; ++field)
        {
            std::vector<Complex> ours, theirs;
            for (unsigned raw = 0; raw < 64; ++raw)
            {
                const auto& r = ref[(i * 2 + field) * 64 + raw];
                ASSERT_EQ(unsigned(r[1]), field + 1);
                const Complex expected(r[4], r[3]);
                const int k = raw < 32 ? int(raw) : int(raw) - 64;
                const Complex got = f.at(field, 0, unsigned(k + 32));
                EXPECT_EQ(got, expected) << "line " << i << " field " << field << " k " << k;
                if (k != 0 && std::abs(k) <= 28)
                {
                    ours.push_back(got);
                    theirs.push_back(expected);
                }
            }
            EXPECT_GE(correlation(ours, theirs), 0.9999);
        }
    }
}

// The other rows of ESP-IDF's table: which fields, over which subcarriers, on which channel.
TEST(Esp32, BufferLayoutFollowsEspIdfTable)
{
    struct Row
    {
        int secondary;
        unsigned sigMode, cwb, stbc, values;
        std::vector<size_t> entries;  // per field
        unsigned bw;
        size_t htMeasured;  // subcarriers of the HT-LTF (0: none)
    };
    const std::vector<Row> rows = {
        {0, 0, 0, 0, 128, {64}, 20, 0},
        {0, 1, 0, 0, 256, {64, 64}, 20, 56},
        {2, 0, 0, 0, 128, {64}, 40, 0},
        {2, 1, 0, 1, 380, {64, 63, 63}, 40, 56},
        {2, 1, 1, 0, 384, {64, 128}, 40, 114},
        {2, 1, 1, 1, 612, {64, 121, 121}, 40, 114},
        {1, 1, 0, 0, 256, {64, 64}, 40, 56},
        {1, 1, 0, 1, 376, {64, 62, 62}, 40, 56},
        {1, 1, 1, 1, 612, {64, 121, 121}, 40, 114}};
    for (const auto& row : rows)
    {
        esp32::Esp32Line l;
        l.hasPacketInfo = true;
        l.secondaryChannel = row.secondary;
        l.sigMode = row.sigMode;
        l.cwb = row.cwb;
        l.stbc = row.stbc;
        l.channel = 6;
        l.values.assign(row.values, 1);
        const auto layout = esp32::bufferLayout(l);
        const std::string where = "secondary " + std::to_string(row.secondary) + " sig_mode " +
                                  std::to_string(row.sigMode) + " cwb " + std::to_string(row.cwb) +
                                  " stbc " + std::to_string(row.stbc);
        EXPECT_TRUE(layout.matchedTable) << where;
        EXPECT_EQ(layout.bandwidthMHz, row.bw) << where;
        ASSERT_EQ(layout.blocks.size(), row.entries.size()) << where;
        for (size_t b = 0; b < row.entries.size(); ++b)
            EXPECT_EQ(layout.blocks[b].k.size(), row.entries[b]) << where << " field " << b;
        EXPECT_EQ(layout.blocks[0].measured.size(), 52u) << where;
        if (row.htMeasured)
        {
            EXPECT_EQ(layout.blocks[1].measured.size(), row.htMeasured) << where;
        }
        // The L-LTF sits on the primary 20 MHz: the upper half of the 40 MHz channel when the
        // secondary one is below (2), the lower half when above (1).
        if (row.secondary == 2)
        {
            EXPECT_EQ(layout.blocks[0].measured.front(), 32 - 26) << where;
        }
        if (row.secondary == 1)
        {
            EXPECT_EQ(layout.blocks[0].measured.back(), -32 + 26) << where;
        }

        CObservationWiFiCSI obs;
        std::string why;
        ASSERT_TRUE(esp32::toObservation(l, obs, why)) << where << ": " << why;
        EXPECT_EQ(obs.nTx, row.stbc && row.sigMode == 1 ? 2 : 1) << where;
        EXPECT_EQ(obs.chanspec.bandwidthMHz, row.bw) << where;
        if (row.secondary == 2)
        {
            EXPECT_EQ(obs.chanspec.asBroadcomString(), "6/40") << where;
        }
    }
    // A length the table doesn't give (an LTF disabled in wifi_csi_config_t): the L-LTF only.
    esp32::Esp32Line l;
    l.hasPacketInfo = true;
    l.sigMode = 1;
    l.values.assign(200, 1);
    const auto layout = esp32::bufferLayout(l);
    EXPECT_FALSE(layout.matchedTable);
    ASSERT_EQ(layout.blocks.size(), 1u);
    EXPECT_EQ(layout.blocks[0].kind, esp32::LtfBlock::Kind::LLTF);
}

// --------------------------------------------------------------------------- Atheros
// The first 8 records of a public Atheros CSI Tool log against the tool's own reader
// (read_log_file + read_csi, run in Octave; it returns the first 6): every value equal.
TEST(Atheros, MatchesTheCsiToolsReader)
{
    CsiDecodeSummary s;
    const auto frames = decodeAll(data("atheros/ath_csi_1.first8.dat"), "auto", &s);
    EXPECT_EQ(s.format, "atheros");
    ASSERT_EQ(frames.size(), 8u);
    const auto ref = readCsv(data("atheros/ath_csi_1.first8.reference.csv"));
    const auto meta = readCsv(data("atheros/ath_csi_1.first8.reference_meta.csv"));
    ASSERT_EQ(meta.size(), 6u);
    ASSERT_EQ(ref.size(), 6u * 3 * 2 * 56);
    std::map<std::array<int, 4>, Complex> expected;  // record, rx, tx, tone
    for (const auto& r : ref)
        expected[{int(r[0]), int(r[1]), int(r[2]), int(r[3])}] = Complex(float(r[4]), float(r[5]));
    const auto& ks = atheros::toneSubcarriers(56);
    for (size_t i = 0; i < meta.size(); ++i)
    {
        const auto& f = *frames[i];
        EXPECT_EQ(f.source, "ar9300");
        EXPECT_EQ(f.nRx, 3);
        EXPECT_EQ(f.nTx, 2);
        EXPECT_TRUE(f.isComplete());
        EXPECT_EQ(f.chanspec.asString(), "6/20");
        EXPECT_EQ(f.dataSubcarriers().size(), 56u);
        EXPECT_NEAR(mrpt::Clock::toDouble(f.timestamp), meta[i][1] * 1e-6, 1e-6);
        ASSERT_EQ(f.antennaRssi_dB.size(), 3u);
        EXPECT_EQ(f.antennaRssi_dB[0], float(meta[i][10]));
        EXPECT_EQ(f.antennaRssi_dB[2], float(meta[i][12]));
        for (unsigned tx = 0; tx < 2; ++tx)
            for (unsigned rx = 0; rx < 3; ++rx)
            {
                std::vector<Complex> ours, theirs;
                for (unsigned t = 0; t < 56; ++t)
                {
                    const Complex want = expected.at({int(i), int(rx), int(tx), int(t)});
                    const Complex got = f.at(tx, rx, subcarrierToBin(ks[t], 64));
                    EXPECT_EQ(got, want)
                        << "record " << i << " rx " << rx << " tx " << tx << " tone " << t;
                    ours.push_back(got);
                    theirs.push_back(want);
                }
                EXPECT_GE(correlation(ours, theirs), 0.9999);
            }
    }
}

// --------------------------------------------------------------------------- detection
TEST(CsiDecoders, DetectedByContentNotByName)
{
    test::TempDir tmp;
    const std::map<std::string, std::string> samples = {
        {"nexmon/bcm4358-80mhz.pcap", "nexmon"},
        {"intel5300/log.all_csi.6.7.6.dat", "intel5300"},
        {"esp32/csi_data.csv", "esp32"},
        {"atheros/ath_csi_1.first8.dat", "atheros"},
        {"rawlog/v0-bcm4366c0.rawlog", "rawlog"}};
    for (const auto& [file, format] : samples)
    {
        // Misleading names: the extension must not matter.
        const std::string renamed = tmp.file("capture-" + format + ".pcap.txt");
        std::filesystem::copy_file(
            data(file), renamed, std::filesystem::copy_options::overwrite_existing);
        EXPECT_EQ(CsiDecoderRegistry::instance().detect(renamed)->name(), format) << file;
    }
    std::ofstream(tmp.file("junk.bin")) << "hello, this is no CSI at all\n";
    EXPECT_THROW(CsiDecoderRegistry::instance().detect(tmp.file("junk.bin")), std::runtime_error);
    CsiDecodeOptions o;
    EXPECT_THROW(applyFormatOption("picoscenes", o), std::invalid_argument);
    EXPECT_EQ(applyFormatOption("ubilocate", o), "nexmon");
    EXPECT_EQ(o.assembler.format, nexmon::FormatHint::UbiLocate);
}

// --------------------------------------------------------------------------- bad input
template <typename F>
CsiDecodeError expectDecodeError(F&& f)
{
    try
    {
        f();
    }
    catch (const CsiDecodeError& e)
    {
        return e;
    }
    ADD_FAILURE() << "no CsiDecodeError";
    return CsiDecodeError("", 0, "", "");
}

/** Options that stop at the first malformed record (the CLIs' --strict). */
CsiDecodeOptions strictOptions()
{
    CsiDecodeOptions o;
    o.strict = true;
    return o;
}

std::string writeBytes(test::TempDir& tmp, const std::string& name, const std::vector<uint8_t>& b)
{
    const std::string path = tmp.file(name);
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(b.data()), long(b.size()));
    return path;
}

bool hasNote(const CsiDecodeSummary& s, const std::string& text)
{
    for (const auto& n : s.notes)
        if (n.find(text) != std::string::npos) return true;
    return false;
}

TEST(CsiDecoders, TruncatedLastIntelRecordIsANote)
{
    // A capture that was stopped: the records before the cut are all there, the cut one is a
    // note (strict or not), not an error.
    test::TempDir tmp;
    auto bytes = readWholeFile(data("intel5300/log.all_csi.6.7.6.dat"));
    bytes.resize(bytes.size() - 100);  // cut inside the last record
    const std::string path = writeBytes(tmp, "cut.dat", bytes);
    for (const bool strict : {false, true})
    {
        std::vector<CObservationWiFiCSI::Ptr> frames;
        CsiDecodeSummary s;
        CsiDecodeOptions o;
        o.strict = strict;
        decodeCsiFile(
            path, "auto", o, [&](auto&& f) { frames.push_back(f); }, {}, &s);
        EXPECT_EQ(s.format, "intel5300");
        EXPECT_GE(frames.size(), 27u);
        EXPECT_LT(frames.size(), 29u);
        EXPECT_TRUE(hasNote(s, "is truncated")) << s.asString();
        EXPECT_EQ(s.rejectedRecords(), 0u);
    }
    // Cut inside its first record: not this format, or nothing to keep: an error.
    bytes.resize(100);
    const auto e = expectDecodeError(
        [&] { decodeCsiFile(writeBytes(tmp, "head.dat", bytes), "intel5300", {}, [](auto&&) {}); });
    EXPECT_EQ(e.offset, 0u);
}

TEST(CsiDecoders, BadIntelRecordIsSkippedAndCountedOrStopsWhenStrict)
{
    test::TempDir tmp;
    auto bytes = readWholeFile(data("intel5300/log.all_csi.6.7.6.dat"));
    const auto all = decodeAll(data("intel5300/log.all_csi.6.7.6.dat"));
    // Second and third records: Nrx at payload byte 8 (after the 3-byte length + code).
    const size_t first = size_t(bytes[0] << 8 | bytes[1]) + 2;
    const size_t second = first + size_t(bytes[first] << 8 | bytes[first + 1]) + 2;
    bytes[first + 3 + 8] = 5;
    bytes[second + 3 + 8] = 4;
    const std::string path = writeBytes(tmp, "nrx5.dat", bytes);

    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiDecodeSummary s;
    decodeCsiFile(
        path, "intel5300", {}, [&](auto&& f) { frames.push_back(f); }, {}, &s);
    EXPECT_EQ(frames.size(), all.size() - 2);  // every other record is still there
    ASSERT_EQ(s.rejected.size(), 1u) << s.asString();
    EXPECT_EQ(s.rejected[0].reason, "impossible antenna counts");
    EXPECT_EQ(s.rejected[0].count, 2u);
    EXPECT_EQ(s.rejected[0].firstOffset, first);
    EXPECT_NE(s.rejected[0].firstWhere.find("Nrx=5"), std::string::npos);
    EXPECT_NE(
        s.asString().find("skipped 2 malformed records: impossible antenna counts"),
        std::string::npos)
        << s.asString();

    frames.clear();
    const auto e = expectDecodeError(
        [&] {
            decodeCsiFile(
                path, "intel5300", strictOptions(), [&](auto&& f) { frames.push_back(f); });
        });
    EXPECT_EQ(e.offset, first);
    EXPECT_NE(std::string(e.what()).find("Nrx=5"), std::string::npos) << e.what();
    EXPECT_EQ(frames.size(), 1u);
}

TEST(CsiDecoders, IntelRecordLongerThanItsPayloadIsReadAsWsrOrRefused)
{
    // The WSR Toolbox writes 18 more bytes between the header and the CSI; they were decoded
    // as CSI (garbage, no warning). Now 18 bytes are read as its trailer (host time, sender
    // MAC, frame counter) and the CSI after them; any other surplus is refused.
    test::TempDir tmp;
    const auto bytes = readWholeFile(data("intel5300/log.all_csi.6.7.6.dat"));
    const auto plain = decodeAll(data("intel5300/log.all_csi.6.7.6.dat"));
    ASSERT_GE(plain.size(), 4u);
    for (const size_t extra : {size_t(18), size_t(5)})
    {
        std::vector<uint8_t> rec;
        size_t pos = 0, n = 0;
        while (pos + 3 <= bytes.size() && n < 4)
        {
            const size_t len = size_t(bytes[pos] << 8 | bytes[pos + 1]);
            const size_t outLen = len + extra;
            rec.push_back(uint8_t(outLen >> 8));
            rec.push_back(uint8_t(outLen & 0xFF));
            // code + 20-byte header, the extra block, then the CSI payload
            rec.insert(
                rec.end(), bytes.begin() + long(pos + 2), bytes.begin() + long(pos + 2 + 21));
            std::vector<uint8_t> trailer(extra, uint8_t(0xAB));
            if (extra == 18)
            {
                // 1 000 000 000 s + 250 000 µs, MAC 02:00:00:00:00:0n, counter 70 000 + n
                trailer = {0x00, 0xCA, 0x9A, 0x3B, 0x90,       0xD0, 0x03, 0x00, 0x02,
                           0x00, 0x00, 0x00, 0x00, uint8_t(n), 0,    0,    0,    0};
                const uint32_t count = 70000 + uint32_t(n);
                for (int i = 0; i < 4; ++i) trailer[size_t(14 + i)] = uint8_t(count >> (8 * i));
            }
            rec.insert(rec.end(), trailer.begin(), trailer.end());
            rec.insert(
                rec.end(), bytes.begin() + long(pos + 2 + 21), bytes.begin() + long(pos + 2 + len));
            pos += 2 + len, ++n;
        }
        ASSERT_EQ(n, 4u);
        const std::string path = writeBytes(tmp, "wsr" + std::to_string(extra) + ".dat", rec);
        std::vector<CObservationWiFiCSI::Ptr> frames;
        CsiDecodeSummary s;
        decodeCsiFile(
            path, extra == 18 ? "auto" : "intel5300", {}, [&](auto&& f) { frames.push_back(f); },
            {}, &s);
        if (extra == 18)
        {
            EXPECT_EQ(s.format, "intel5300");
            ASSERT_EQ(frames.size(), 4u) << s.asString();
            for (size_t i = 0; i < 4; ++i)
            {
                EXPECT_EQ(frames[i]->csi, plain[i]->csi) << "record " << i;
                EXPECT_EQ(frames[i]->source, "iwl5300-wsr");
                EXPECT_EQ(
                    frames[i]->transmitter.asString(), "02:00:00:00:00:0" + std::to_string(i));
                EXPECT_EQ(frames[i]->firmwareCounter, uint16_t((70000 + i) & 0xFFFF));
                EXPECT_NEAR(mrpt::Clock::toDouble(frames[i]->timestamp), 1e9 + 0.25, 1e-5);
            }
            EXPECT_TRUE(hasNote(s, "WSR Toolbox records")) << s.asString();
        }
        else
        {
            EXPECT_TRUE(frames.empty());
            ASSERT_EQ(s.rejected.size(), 1u) << s.asString();
            EXPECT_EQ(s.rejected[0].count, 4u);
            EXPECT_NE(s.rejected[0].reason.find("record length disagrees"), std::string::npos)
                << s.rejected[0].reason;
        }
    }
}

TEST(CsiDecoders, RealWsrRecordingIsReadWithItsTrailer)
{
    // A real WSR Toolbox recording (../shared/data/wsr, LOS_Set_A), compared with an
    // independent reading of its bytes (tests/data/wsr-reference/read_wsr_records.py): every
    // record decoded, senders and counters as the trailer says, the CSI value for value, the
    // cut last record a note.
    const std::string shared = test::sharedDir();
    const std::string path = shared +
                             "/data/wsr/Dataset/2D-Displacement_raw_data/LOS_Set_A/"
                             "0627_2D-multi-link_A_L2/csi_rx_2021-06-27_204307.dat";
    if (shared.empty() || !std::filesystem::exists(path))
        GTEST_SKIP() << "WSR recording not found (../shared absent)";
    CsiDecodeSummary s;
    const auto frames = decodeAll(path, "auto", &s);
    EXPECT_EQ(s.format, "intel5300");
    EXPECT_TRUE(s.rejected.empty()) << s.asString();
    ASSERT_EQ(frames.size(), 4728u);
    std::map<std::string, size_t> perSender;
    for (const auto& f : frames) ++perSender[f->transmitter.asString()];
    const std::map<std::string, size_t> expectedSenders = {
        {"00:21:6a:30:d2:3c", 1577}, {"00:21:6a:3f:17:5a", 1576}, {"00:21:6a:b2:6e:fa", 1575}};
    EXPECT_EQ(perSender, expectedSenders);
    const auto expectRecord = [](const CObservationWiFiCSI& f, double time, const char* mac,
                                 uint16_t count, const std::vector<std::pair<int, int>>& rx0)
    {
        EXPECT_NEAR(mrpt::Clock::toDouble(f.timestamp), time, 2e-6);
        EXPECT_EQ(f.transmitter.asString(), mac);
        EXPECT_EQ(f.firmwareCounter, count);
        ASSERT_EQ(f.nRx, 3);
        ASSERT_EQ(f.nTx, 1);
        ASSERT_EQ(f.subcarrierIndices.size(), rx0.size());
        for (size_t g = 0; g < rx0.size(); ++g)
        {
            const auto v = f.at(0, 0, subcarrierToBin(f.subcarrierIndices[g], f.nfft()));
            EXPECT_EQ(v, CObservationWiFiCSI::Complex(float(rx0[g].first), float(rx0[g].second)))
                << "subcarrier group " << g;
        }
    };
    expectRecord(
        *frames.front(), 1624840955.555331, "00:21:6a:30:d2:3c", 1,
        {{0, -17},  {-20, -9}, {-17, 16}, {7, 23},    {26, 5},   {19, -22},  {-5, -29},  {-26, -13},
         {-25, 14}, {-3, 30},  {21, 20},  {29, -5},   {15, -27}, {-11, -27}, {-21, -20}, {-28, 6},
         {-12, 25}, {11, 24},  {26, 7},   {23, -16},  {4, -29},  {-20, -21}, {-32, 5},   {-17, 30},
         {18, 30},  {38, 1},   {18, -35}, {-25, -29}, {-34, 13}, {-17, 26}});
    expectRecord(
        *frames.back(), 1624840968.478749, "00:21:6a:b2:6e:fa", 1577,
        {{9, -26},   {-24, -24}, {-30, 7},  {-13, 29}, {16, 29}, {34, 8},  {28, -18}, {7, -34},
         {-21, -33}, {-40, -6},  {-32, 22}, {-7, 38},  {24, 28}, {37, 3},  {36, -14}, {15, -33},
         {-13, -32}, {-30, -14}, {-30, 10}, {-13, 26}, {10, 27}, {24, 11}, {24, -7},  {12, -20},
         {-6, -25},  {-23, -12}, {-24, 11}, {-2, 28},  {21, 14}, {24, 0}});
    EXPECT_TRUE(hasNote(s, "is truncated")) << s.asString();
    EXPECT_TRUE(hasNote(s, "WSR Toolbox records")) << s.asString();
}

TEST(CsiDecoders, FileOfAnotherFormatIsAClearError)
{
    // An ESP32 log forced through the Intel decoder, and an Intel log through the ESP32 one.
    const auto e1 = expectDecodeError(
        [&] { decodeCsiFile(data("esp32/csi_data.csv"), "intel5300", {}, [](auto&&) {}); });
    EXPECT_EQ(e1.format, "intel5300");
    EXPECT_EQ(e1.offset, 0u);
    std::vector<CObservationWiFiCSI::Ptr> frames;
    decodeCsiFile(
        data("intel5300/log.all_csi.6.7.6.dat"), "esp32", {},
        [&](auto&& f) { frames.push_back(f); });
    EXPECT_TRUE(frames.empty());  // no CSI_DATA line in a binary file: nothing, no crash
}

TEST(CsiDecoders, BadEsp32LineIsSkippedAndNamedOrStopsWhenStrict)
{
    test::TempDir tmp;
    std::string text = test::readFile(data("esp32/csi_data.csv"));
    const auto all = decodeAll(data("esp32/csi_data.csv"));
    const size_t third = text.find('\n', text.find('\n') + 1) + 1;
    const size_t cut = text.find('\n', third + 200);
    text.erase(third + 200, cut - (third + 200));  // line 3 loses values and its bracket
    const std::string path = tmp.file("cut.csv");
    std::ofstream(path) << text;

    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiDecodeSummary s;
    decodeCsiFile(
        path, "auto", {}, [&](auto&& f) { frames.push_back(f); }, {}, &s);
    EXPECT_EQ(frames.size(), all.size() - 1);
    ASSERT_EQ(s.rejected.size(), 1u) << s.asString();
    EXPECT_EQ(s.rejected[0].firstOffset, third);
    EXPECT_EQ(s.rejected[0].firstWhere.rfind("line 3", 0), 0u) << s.rejected[0].firstWhere;

    frames.clear();
    const auto e = expectDecodeError(
        [&]
        { decodeCsiFile(path, "auto", strictOptions(), [&](auto&& f) { frames.push_back(f); }); });
    EXPECT_EQ(e.format, "esp32");
    EXPECT_EQ(e.offset, third);
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
    EXPECT_EQ(frames.size(), 2u);

    // The last line cut off (no newline): a note, the others all read.
    std::string tail = test::readFile(data("esp32/csi_data.csv"));
    while (!tail.empty() && tail.back() == '\n') tail.pop_back();
    tail.resize(tail.size() - 40);
    std::ofstream(tmp.file("tail.csv")) << tail;
    CsiDecodeSummary st;
    frames.clear();
    decodeCsiFile(
        tmp.file("tail.csv"), "auto", strictOptions(), [&](auto&& f) { frames.push_back(f); }, {},
        &st);
    EXPECT_EQ(frames.size(), all.size() - 1);
    EXPECT_TRUE(hasNote(st, "is cut off")) << st.asString();
}

// --------------------------------------------------------------------------- observation
TEST(CsiObservationV1, OldRawlogStillLoadsAndEqualsAFreshDecode)
{
    CsiDecodeSummary s;
    const auto old = decodeAll(data("rawlog/v0-bcm4366c0.rawlog"), "auto", &s);
    EXPECT_EQ(s.format, "rawlog");
    const auto fresh = decodeAll(data("nexmon/bcm4366c0-80mhz.pcap"));
    ASSERT_EQ(old.size(), 8u);
    ASSERT_EQ(fresh.size(), old.size());
    for (size_t i = 0; i < old.size(); ++i)
    {
        EXPECT_EQ(old[i]->source, "bcm4366c0");
        EXPECT_TRUE(old[i]->subcarrierIndices.empty());
        EXPECT_TRUE(std::isnan(old[i]->noiseFloor_dBm));
        EXPECT_EQ(old[i]->sequenceNumber, fresh[i]->sequenceNumber);
        // The capture has core 0 only: the old rawlog held four rows with three missing, a
        // fresh decode holds the one core the router reported (issue 54).
        EXPECT_EQ(old[i]->nRx, 4);
        EXPECT_EQ(old[i]->presentPairs(), 1u);
        EXPECT_EQ(fresh[i]->nRx, 1);
        EXPECT_TRUE(fresh[i]->isComplete());
        EXPECT_TRUE(std::equal(
            old[i]->pair(0, 0), old[i]->pair(0, 0) + old[i]->nfft(), fresh[i]->pair(0, 0)));
        EXPECT_EQ(old[i]->dataSubcarriers().size(), 234u);
    }
}

TEST(CsiObservationV1, NewFieldsRoundTripThroughARawlog)
{
    const auto frames = decodeAll(data("intel5300/log.all_csi.6.7.6.dat"));
    ASSERT_FALSE(frames.empty());
    test::TempDir tmp;
    const std::string path = tmp.file("intel.rawlog");
    {
        mrpt::io::CFileGZOutputStream out(path);
        auto a = mrpt::serialization::archiveFrom(out);
        a << *frames[0];
    }
    const auto back = decodeAll(path);
    ASSERT_EQ(back.size(), 1u);
    const auto& a = *frames[0];
    const auto& b = *back[0];
    EXPECT_EQ(b.source, a.source);
    EXPECT_EQ(b.subcarrierIndices, a.subcarrierIndices);
    EXPECT_EQ(b.antennaRssi_dB, a.antennaRssi_dB);
    EXPECT_EQ(b.agc_dB, a.agc_dB);
    EXPECT_EQ(b.scaledCsiFactor, a.scaledCsiFactor);
    EXPECT_EQ(b.csi, a.csi);
    std::ostringstream desc;
    b.getDescriptionAsText(desc);
    EXPECT_NE(desc.str().find("iwl5300"), std::string::npos);
    EXPECT_NE(desc.str().find("30 reported"), std::string::npos);
    // exportTxt: 9 metadata columns + re/im of 1 x 3 pairs x 30 subcarriers.
    std::istringstream row(b.exportTxtDataRow());
    size_t columns = 0;
    for (std::string c; row >> c;) ++columns;
    EXPECT_EQ(columns, 9u + 2u * 3u * 30u);
}

// --------------------------------------------------------------------------- bearings
TEST(CsiSourceBearings, OneAntennaGivesNoAngleSaidClearlyMultiAntennaIsProcessed)
{
    const auto array =
        AntennaArray::fromYamlFile(test::sourceDir() + "/share/arrays/ap-linear-4.yaml");
    CsiPreprocessor pre(PreprocessOptions{}, array);
    CleanCsi clean;
    const auto esp = decodeAll(data("esp32/csi_data.csv"));
    ASSERT_FALSE(esp.empty());
    const auto why = pre.process(*esp[0], clean);
    EXPECT_EQ(why, RejectReason::SingleAntenna);
    EXPECT_NE(std::string(toString(why)).find("no angle of arrival"), std::string::npos);
    // The Intel 5300's 3 antennas on a given array are processed.
    const auto intel = decodeAll(data("intel5300/log.all_csi.6.7.6.dat"));
    ASSERT_FALSE(intel.empty());
    EXPECT_EQ(pre.process(*intel[0], clean), RejectReason::Accepted);
    EXPECT_EQ(clean.nRx, 3u);
}

// --------------------------------------------------------------------------- CLIs
TEST(CsiSourcesCli, ImportAndExportEveryFormat)
{
    test::TempDir tmp;
    for (const char* file :
         {"intel5300/log.all_csi.6.7.6.dat", "esp32/csi_data.csv", "nexmon/bcm43455c0-80mhz.pcap",
          "atheros/ath_csi_1.first8.dat", "esp32-csi-tool/example_data.first20.csv"})
    {
        const std::string rawlog = tmp.file("out.rawlog");
        const auto imp = test::run(test::binDir() + "/csi-import -q " + data(file) + " " + rawlog);
        EXPECT_EQ(imp.exitCode, 0) << imp.output;
        const auto exp = test::run(test::binDir() + "/csi-export -q --jsonl - " + rawlog);
        EXPECT_EQ(exp.exitCode, 0) << exp.output;
        EXPECT_NE(exp.output.find("\"source\":"), std::string::npos);
        EXPECT_NE(exp.output.find("\"subcarriers\":["), std::string::npos);
    }
    // ESP32-CSI-Tool (issue 20.1: both programs stopped at row 2): every row, straight from the
    // log.
    const auto csiTool = test::run(
        test::binDir() + "/csi-export -q --jsonl " + tmp.file("tool.jsonl") + " " +
        data("esp32-csi-tool/example_data.first20.csv"));
    EXPECT_EQ(csiTool.exitCode, 0) << csiTool.output;
    EXPECT_NE(csiTool.output.find("CSI frames: 20"), std::string::npos) << csiTool.output;
    const auto j = test::run(
        test::binDir() + "/csi-export -q --jsonl - " + data("intel5300/log.all_csi.6.7.6.dat"));
    EXPECT_EQ(j.exitCode, 0);
    EXPECT_NE(j.output.find("\"source\":\"iwl5300\",\"subcarriers\":[-28,-26,"), std::string::npos);
    // The old name still works, and bad input exits non-zero naming file, offset and format.
    test::TempDir t2;
    auto bytes = readWholeFile(data("intel5300/log.all_csi.6.7.6.dat"));
    bytes.resize(bytes.size() - 100);
    std::ofstream(t2.file("cut.dat"), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    // A capture that was stopped: converted, its cut last record a note.
    const auto cutRun = test::run(
        test::binDir() + "/csi-pcap2rawlog -q " + t2.file("cut.dat") + " " + t2.file("o.rawlog"));
    EXPECT_EQ(cutRun.exitCode, 0) << cutRun.output;
    EXPECT_NE(cutRun.output.find("is truncated"), std::string::npos) << cutRun.output;
    // A malformed record in the middle: skipped and counted, exit 3; --strict stops there.
    bytes = readWholeFile(data("intel5300/log.all_csi.6.7.6.dat"));
    const size_t first = size_t(bytes[0] << 8 | bytes[1]) + 2;
    bytes[first + 3 + 8] = 5;  // Nrx of the second record
    std::ofstream(t2.file("bad.dat"), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    for (const std::string tool : {"csi-import", "csi-export"})
    {
        const std::string out =
            tool == "csi-import" ? t2.file("b.rawlog") : "--jsonl " + t2.file("b.jsonl");
        const auto skip =
            test::run(test::binDir() + "/" + tool + " -q " + t2.file("bad.dat") + " " + out);
        EXPECT_EQ(skip.exitCode, 3) << skip.output;
        EXPECT_NE(
            skip.output.find(
                "skipped 1 malformed record: impossible antenna counts (first at byte " +
                std::to_string(first)),
            std::string::npos)
            << skip.output;
        const auto strict = test::run(
            test::binDir() + "/" + tool + " -q --strict " + t2.file("bad.dat") + " " + out);
        EXPECT_EQ(strict.exitCode, 1) << strict.output;
        EXPECT_NE(
            strict.output.find("bad.dat' at byte " + std::to_string(first)), std::string::npos)
            << strict.output;
        EXPECT_NE(strict.output.find("intel5300 format"), std::string::npos) << strict.output;
    }
}

}  // namespace

TEST(Atheros, BadRecordsAreSkippedAndCountedATruncatedTailIsANote)
{
    test::TempDir tmp;
    const std::string text = test::readFile(data("atheros/ath_csi_1.first8.dat"));
    // Truncated in the third record (each record is 2 + 1905 bytes): two frames, and a note.
    const std::string cut = tmp.file("cut.dat");
    std::ofstream(cut, std::ios::binary) << text.substr(0, 2 * 1907 + 900);
    std::vector<CObservationWiFiCSI::Ptr> got;
    CsiDecodeSummary s;
    decodeCsiFile(
        cut, "atheros", strictOptions(), [&](CObservationWiFiCSI::Ptr&& f) { got.push_back(f); },
        {}, &s);
    EXPECT_EQ(got.size(), 2u);
    EXPECT_TRUE(hasNote(s, "(byte 3814) is truncated")) << s.asString();
    // Impossible antenna count in the second record's status (nr at byte 2 + 17).
    std::string bad = text;
    bad[1907 + 2 + 17] = 7;
    const std::string badPath = tmp.file("bad.dat");
    std::ofstream(badPath, std::ios::binary) << bad;
    got.clear();
    CsiDecodeSummary sb;
    decodeCsiFile(
        badPath, "atheros", {}, [&](auto&& f) { got.push_back(f); }, {}, &sb);
    EXPECT_EQ(got.size(), 7u);
    ASSERT_EQ(sb.rejected.size(), 1u) << sb.asString();
    EXPECT_EQ(sb.rejected[0].firstOffset, 1907u);
    EXPECT_NE(sb.rejected[0].firstWhere.find("nr=7"), std::string::npos);
    const auto e2 = expectDecodeError(
        [&] { decodeCsiFile(badPath, "atheros", strictOptions(), [](auto&&) {}); });
    EXPECT_EQ(e2.offset, 1907u);
    EXPECT_NE(std::string(e2.what()).find("nr=7"), std::string::npos) << e2.what();
}
