#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::nexmon;

namespace
{
uint32_t word(bool realNeg, uint32_t mr, bool imagNeg, uint32_t mi, int exponent)
{
    return (uint32_t(realNeg) << 29) | (mr << 18) | (uint32_t(imagNeg) << 17) | (mi << 6) |
           (uint32_t(exponent) & 0x3F);
}
}  // namespace

TEST(NexmonWords, HandBuiltGoldenWords)
{
    // (5 - 3j) * 2^-2, exponent field 0x3E
    EXPECT_EQ(unpackWord(word(false, 5, true, 3, -2)), std::complex<float>(1.25f, -0.75f));
    // Exponent is two's complement: field 0x3F is -1, not 63.
    EXPECT_EQ(unpackWord(0x3F | (2u << 18)), std::complex<float>(1.0f, 0.0f));
    // Largest positive exponent and mantissa.
    EXPECT_EQ(
        unpackWord(word(true, 2047, false, 1, 31)),
        std::complex<float>(-2047.0f * 2147483648.0f, 2147483648.0f));
    // A zero mantissa is zero, whatever the sign bit (a known bug maps it to +-1).
    EXPECT_EQ(unpackWord(word(true, 0, true, 0, 5)), std::complex<float>(0.0f, 0.0f));
    // A word from the real UbiLocate capture (4x4 file, first datagram, raw word 0).
    EXPECT_EQ(unpackWord(0x273d73f4), std::complex<float>(-463.0f / 4096.0f, 1487.0f / 4096.0f));
}

TEST(NexmonWords, PackUnpackRoundTripWithinQuantisation)
{
    for (const std::complex<float> v :
         {std::complex<float>(1.0f, 0.0f),
          {-0.113037f, 0.363037f},
          {12345.6f, -0.5f},
          {-3e-6f, 7e-6f},
          {0.0f, -42.0f},
          {2047.0f, 2047.0f},
          {2048.0f, 1.0f}})
    {
        const auto back = unpackWord(packWord(v));
        // 11-bit mantissas share one exponent: error at most half a step of the larger part.
        const float step = std::max(std::abs(v.real()), std::abs(v.imag())) / 1024.0f;
        EXPECT_NEAR(back.real(), v.real(), step * 0.5f + 1e-12f) << v;
        EXPECT_NEAR(back.imag(), v.imag(), step * 0.5f + 1e-12f) << v;
    }
    EXPECT_EQ(packWord({0.0f, 0.0f}), 0u);
    EXPECT_EQ(unpackWord(packWord({-0.0f, 0.0f})), std::complex<float>(0.0f, 0.0f));
}

TEST(NexmonWords, DecodeAppliesFftShift)
{
    std::vector<uint8_t> raw(4 * 64);
    for (unsigned i = 0; i < 64; ++i)
    {
        const uint32_t w = word(false, i + 1, false, 0, 0);
        for (int b = 0; b < 4; ++b) raw[4 * i + b] = uint8_t(w >> (8 * b));
    }
    std::vector<std::complex<float>> out(64);
    decodeWords(raw.data(), 64, out.data());
    EXPECT_EQ(out[32].real(), 1.0f);   // raw index 0 (DC) -> bin 32 (k = 0)
    EXPECT_EQ(out[0].real(), 33.0f);   // raw index 32 (k = -32) -> bin 0
    EXPECT_EQ(out[63].real(), 32.0f);  // raw index 31 (k = +31) -> bin 63
}

class NexmonHeaderVariants : public ::testing::TestWithParam<NexmonHeaderVariant>
{
};

TEST_P(NexmonHeaderVariants, EncodeParseRoundTrip)
{
    const auto frame = test::syntheticFrame(4, 4, 80, 1234, "aa:bb:cc:dd:ee:01", GetParam());
    frame->firmwareCounter = GetParam() == NexmonHeaderVariant::UbiLocate ? 77 : 0;
    frame->fragmentNumber = 2;
    std::vector<uint8_t> d;
    encodeDatagram(headerFor(*frame, 3, 2), frame->pair(3, 2), d);
    ASSERT_EQ(d.size(), datagramSize(GetParam(), 256));

    for (const auto hint : {FormatHint::Auto, FormatHint(uint8_t(GetParam()) + 1)})
    {
        DatagramHeader h;
        RejectReason why{};
        ASSERT_TRUE(parseHeader(d.data(), d.size(), hint, h, why)) << toString(why);
        EXPECT_EQ(h.variant, GetParam());
        EXPECT_EQ(h.transmitter.asString(), "aa:bb:cc:dd:ee:01");
        EXPECT_EQ(h.sequenceNumber(), 1234);
        EXPECT_EQ(h.fragmentNumber(), 2);
        EXPECT_EQ(h.core, 2);
        EXPECT_EQ(h.stream, 3);
        EXPECT_EQ(h.chanspec.raw, frame->chanspec.raw);
        if (GetParam() == NexmonHeaderVariant::Nexmon)
        {
            EXPECT_EQ(h.rssi_dBm, -48);
        }
        if (GetParam() == NexmonHeaderVariant::UbiLocate)
        {
            EXPECT_EQ(h.firmwareCounter, 77);
            EXPECT_EQ(h.coreMask, 0x0F);
            EXPECT_EQ(h.streamMask, 0x0F);
        }
        else
        {
            EXPECT_EQ(h.chipId, kChip4366c0);
        }
    }
    std::vector<std::complex<float>> decoded(256);
    decodeWords(d.data() + csiOffset(), 256, decoded.data());
    for (unsigned b = 0; b < 256; ++b)
    {
        const auto v = frame->at(3, 2, b);
        EXPECT_NEAR(std::abs(decoded[b] - v), 0.0f, std::abs(v) / 1024.0f) << b;
    }
}

INSTANTIATE_TEST_SUITE_P(
    AllVariants, NexmonHeaderVariants,
    ::testing::Values(
        NexmonHeaderVariant::Nexmon, NexmonHeaderVariant::NexmonLegacy,
        NexmonHeaderVariant::UbiLocate));

TEST(NexmonHeader, CurrentFirmwareCoreStreamBits)
{
    // csiconf 0x1a00: core = (v>>8)&7 = 2, stream = (v>>11)&7 = 3 on the 4366c0.
    const auto frame = test::syntheticFrame(4, 4);
    std::vector<uint8_t> d;
    encodeDatagram(headerFor(*frame, 3, 2), frame->pair(3, 2), d);
    EXPECT_EQ(d[12], 0x00);
    EXPECT_EQ(d[13], 0x1a);
}

TEST(NexmonHeader, EveryMalformedDatagramHasItsReason)
{
    const auto frame = test::syntheticFrame(1, 1);
    std::vector<uint8_t> good;
    encodeDatagram(headerFor(*frame, 0, 0), frame->pair(0, 0), good);
    const auto reasonFor = [](std::vector<uint8_t> d, FormatHint hint = FormatHint::Auto)
    {
        DatagramHeader h;
        RejectReason why = RejectReason::Count;
        const bool ok = parseHeader(d.data(), d.size(), hint, h, why);
        return ok ? RejectReason::Count : why;
    };
    EXPECT_EQ(reasonFor(good), RejectReason::Count);  // accepted

    EXPECT_EQ(reasonFor({0x11, 0x11, 0x00}), RejectReason::TooShort);
    EXPECT_EQ(reasonFor({}), RejectReason::TooShort);
    auto d = good;
    d[1] = 0x12;
    EXPECT_EQ(reasonFor(d), RejectReason::BadMagic);
    d = good;
    d[16] = 0x45, d[17] = 0x43;  // another chip
    EXPECT_EQ(reasonFor(d), RejectReason::UnknownChip);
    d = good;
    d[15] = 0xe8;  // 160 MHz centred on 155: no such channel
    EXPECT_EQ(reasonFor(d), RejectReason::BadChanspec);
    d = good;
    d[14] = 0x32, d[15] = 0xe8;  // 50/160: a real channel, but 512 words expected, 256 present
    EXPECT_EQ(reasonFor(d), RejectReason::SizeMismatch);
    d = good;
    d.pop_back();
    EXPECT_EQ(reasonFor(d), RejectReason::SizeMismatch);
    d = good;
    d[14] = 0x6a, d[15] = 0xd8;  // 106/40: 128 words expected, 256 present
    EXPECT_EQ(reasonFor(d), RejectReason::SizeMismatch);
    d = good;
    d[13] = 0x05;  // core 5: the chip has four
    EXPECT_EQ(reasonFor(d), RejectReason::BadCoreStream);
    d = good;
    d[13] = 0x20;  // stream 4
    EXPECT_EQ(reasonFor(d), RejectReason::BadCoreStream);
    EXPECT_EQ(reasonFor(good, FormatHint::NexmonLegacy), RejectReason::BadMagic);
    EXPECT_EQ(reasonFor(good, FormatHint::UbiLocate), RejectReason::SizeMismatch);
}

TEST(NexmonHeader, FormatNames)
{
    EXPECT_EQ(formatHintFromString("ubilocate"), FormatHint::UbiLocate);
    EXPECT_EQ(formatHintFromString("nexmon-legacy"), FormatHint::NexmonLegacy);
    EXPECT_THROW(formatHintFromString("nexmon2"), std::invalid_argument);
}
