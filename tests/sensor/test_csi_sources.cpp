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

TEST(CsiDecoders, TruncatedIntelFileKeepsTheRecordsBeforeTheFault)
{
    test::TempDir tmp;
    auto bytes = readWholeFile(data("intel5300/log.all_csi.6.7.6.dat"));
    bytes.resize(bytes.size() - 100);  // cut inside the last record(s)
    const std::string path = tmp.file("cut.dat");
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    std::vector<CObservationWiFiCSI::Ptr> frames;
    const auto e = expectDecodeError(
        [&] { decodeCsiFile(path, "auto", {}, [&](auto&& f) { frames.push_back(f); }); });
    EXPECT_EQ(e.format, "intel5300");
    EXPECT_EQ(e.path, path);
    EXPECT_GT(e.offset, 0u);
    EXPECT_LT(e.offset, bytes.size());
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    EXPECT_GE(frames.size(), 27u);
    EXPECT_LT(frames.size(), 29u);
}

TEST(CsiDecoders, ImpossibleAntennaCountIsNamed)
{
    test::TempDir tmp;
    auto bytes = readWholeFile(data("intel5300/log.all_csi.6.7.6.dat"));
    // Second record: Nrx at payload byte 8 (after the 3-byte length + code).
    const size_t first = size_t(bytes[0] << 8 | bytes[1]) + 2;
    bytes[first + 3 + 8] = 5;
    const std::string path = tmp.file("nrx5.dat");
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    std::vector<CObservationWiFiCSI::Ptr> frames;
    const auto e = expectDecodeError(
        [&] { decodeCsiFile(path, "intel5300", {}, [&](auto&& f) { frames.push_back(f); }); });
    EXPECT_EQ(e.offset, first);
    EXPECT_NE(std::string(e.what()).find("Nrx=5"), std::string::npos) << e.what();
    EXPECT_EQ(frames.size(), 1u);
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

TEST(CsiDecoders, TruncatedEsp32LineNamesTheLine)
{
    test::TempDir tmp;
    std::string text = test::readFile(data("esp32/csi_data.csv"));
    const size_t third = text.find('\n', text.find('\n') + 1) + 1;
    const size_t cut = text.find('\n', third + 200);
    text.erase(third + 200, cut - (third + 200));  // line 3 loses values and its bracket
    const std::string path = tmp.file("cut.csv");
    std::ofstream(path) << text;
    std::vector<CObservationWiFiCSI::Ptr> frames;
    const auto e = expectDecodeError(
        [&] { decodeCsiFile(path, "auto", {}, [&](auto&& f) { frames.push_back(f); }); });
    EXPECT_EQ(e.format, "esp32");
    EXPECT_EQ(e.offset, third);
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
    EXPECT_EQ(frames.size(), 2u);
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
        EXPECT_EQ(old[i]->csi, fresh[i]->csi);
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
          "atheros/ath_csi_1.first8.dat"})
    {
        const std::string rawlog = tmp.file("out.rawlog");
        const auto imp = test::run(test::binDir() + "/csi-import -q " + data(file) + " " + rawlog);
        EXPECT_EQ(imp.exitCode, 0) << imp.output;
        const auto exp = test::run(test::binDir() + "/csi-export -q --jsonl - " + rawlog);
        EXPECT_EQ(exp.exitCode, 0) << exp.output;
        EXPECT_NE(exp.output.find("\"source\":"), std::string::npos);
        EXPECT_NE(exp.output.find("\"subcarriers\":["), std::string::npos);
    }
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
    const auto bad = test::run(
        test::binDir() + "/csi-pcap2rawlog -q " + t2.file("cut.dat") + " " + t2.file("o.rawlog"));
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.output.find("cut.dat' at byte"), std::string::npos) << bad.output;
    EXPECT_NE(bad.output.find("intel5300 format"), std::string::npos) << bad.output;
}

}  // namespace

TEST(Atheros, BadRecordsNameFileOffsetAndFormat)
{
    test::TempDir tmp;
    const std::string text = test::readFile(data("atheros/ath_csi_1.first8.dat"));
    // Truncated in the third record (each record is 2 + 1905 bytes): two frames stay.
    const std::string cut = tmp.file("cut.dat");
    std::ofstream(cut, std::ios::binary) << text.substr(0, 2 * 1907 + 900);
    std::vector<CObservationWiFiCSI::Ptr> got;
    const auto e = expectDecodeError(
        [&] {
            decodeCsiFile(
                cut, "atheros", {}, [&](CObservationWiFiCSI::Ptr&& f) { got.push_back(f); });
        });
    EXPECT_EQ(got.size(), 2u);
    EXPECT_EQ(e.offset, 2u * 1907);
    EXPECT_EQ(e.format, "atheros");
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    // Impossible antenna count in the second record's status (nr at byte 2 + 17).
    std::string bad = text;
    bad[1907 + 2 + 17] = 7;
    const std::string badPath = tmp.file("bad.dat");
    std::ofstream(badPath, std::ios::binary) << bad;
    const auto e2 =
        expectDecodeError([&] { decodeCsiFile(badPath, "atheros", {}, [](auto&&) {}); });
    EXPECT_EQ(e2.offset, 1907u);
    EXPECT_NE(std::string(e2.what()).find("nr=7"), std::string::npos) << e2.what();
}
