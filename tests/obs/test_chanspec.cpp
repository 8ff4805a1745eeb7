#include <gtest/gtest.h>
#include <mrpt_wifi/obs/Chanspec.h>

using mrpt_wifi::Chanspec;
using mrpt_wifi::WifiBand;

TEST(Chanspec, DecodesTheRealCapturesWords)
{
    // 0xe29b: the UbiLocate captures in shared/data/real; 0xe06a / 0xe09b from DESIGN.md.
    const auto a = Chanspec::decode(0xe29b);
    ASSERT_TRUE(a);
    EXPECT_EQ(a->centerChannel, 155);
    EXPECT_EQ(a->bandwidthMHz, 80);
    EXPECT_EQ(a->band, WifiBand::Band5G);
    EXPECT_EQ(a->sideband, 2);
    EXPECT_EQ(a->controlChannel(), 157u);  // 149 153 [157] 161
    EXPECT_EQ(a->nfft(), 256u);
    EXPECT_DOUBLE_EQ(a->centerFrequencyHz(), 5775e6);

    const auto b = Chanspec::decode(0xe06a);
    ASSERT_TRUE(b);
    EXPECT_EQ(b->centerChannel, 106);
    EXPECT_EQ(b->sideband, 0);
    EXPECT_EQ(b->controlChannel(), 100u);
    EXPECT_EQ(b->asString(), "106/80");
}

TEST(Chanspec, MakeAndDecodeRoundTripEveryBandwidth)
{
    struct Case
    {
        unsigned ch, bw, nfft;
        double fc;
    };
    for (const Case c :
         {Case{36, 20, 64, 5180e6}, Case{38, 40, 128, 5190e6}, Case{42, 80, 256, 5210e6},
          Case{6, 20, 64, 2437e6}, Case{14, 20, 64, 2484e6}, Case{155, 80, 256, 5775e6},
          Case{50, 160, 512, 5250e6}, Case{114, 160, 512, 5570e6}, Case{163, 160, 512, 5815e6}})
    {
        const auto cs = Chanspec::make(c.ch, c.bw);
        const auto back = Chanspec::decode(cs.raw);
        ASSERT_TRUE(back) << c.ch << "/" << c.bw;
        EXPECT_EQ(back->centerChannel, c.ch);
        EXPECT_EQ(back->bandwidthMHz, c.bw);
        EXPECT_EQ(back->nfft(), c.nfft);
        EXPECT_DOUBLE_EQ(back->centerFrequencyHz(), c.fc);
        EXPECT_EQ(Chanspec::fromString(cs.asString()), cs);
    }
    EXPECT_EQ(Chanspec::make(155, 80).raw, 0xe09b);
}

TEST(Chanspec, RejectsWhatTheChipCannotUse)
{
    EXPECT_FALSE(Chanspec::decode(0xe89b));  // 160 MHz centred on 155: no such channel
    EXPECT_FALSE(Chanspec::decode(0xf02a));  // bandwidth code 6: 80+80 (channel indices)
    EXPECT_FALSE(Chanspec::decode(0x2806));  // 160 MHz at 2.4 GHz
    EXPECT_FALSE(Chanspec::decode(0x609b));  // band bits 01: not 2.4 or 5 GHz
    EXPECT_FALSE(Chanspec::decode(0xe000));  // channel 0
    EXPECT_FALSE(Chanspec::decode(0x2006));  // 80 MHz at 2.4 GHz
    EXPECT_FALSE(Chanspec::decode(0xe49b));  // 80 MHz has sidebands 0..3 only
    EXPECT_THROW(Chanspec::make(155, 160), std::invalid_argument);
    EXPECT_THROW(Chanspec::fromString("155/"), std::invalid_argument);
    EXPECT_THROW(Chanspec::fromString("abc"), std::invalid_argument);
    EXPECT_THROW(Chanspec::fromString("155/80x"), std::invalid_argument);
    try
    {
        Chanspec::fromString("155/70");
        FAIL();
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("155/70"), std::string::npos) << e.what();
    }
}

TEST(Chanspec, BroadcomControlChannelNotation)
{
    // wl / makecsiparams name a wide channel by its control channel: 157/80 is center 155.
    const auto cs = Chanspec::fromString("157/80");
    EXPECT_EQ(cs.centerChannel, 155);
    EXPECT_EQ(cs.sideband, 2);
    EXPECT_EQ(cs.raw, 0xe29b);  // the real captures' chanspec
    EXPECT_EQ(cs.asBroadcomString(), "157/80");
    EXPECT_EQ(cs.asString(), "155/80");
    EXPECT_EQ(Chanspec::fromString("36/80").centerChannel, 42);
    EXPECT_EQ(Chanspec::fromString("36/80").sideband, 0);
    EXPECT_EQ(Chanspec::fromString("48/80").sideband, 3);
    EXPECT_EQ(Chanspec::fromString("42/80").centerChannel, 42);  // center notation still works
    EXPECT_EQ(Chanspec::fromString("153/40").centerChannel, 151);
    EXPECT_EQ(Chanspec::fromString("153/40").sideband, 1);
    EXPECT_EQ(Chanspec::fromString("106/80").raw, 0xe06a);
    EXPECT_FALSE(Chanspec::fromControlChannel(150, 80));
    // 160 MHz: eight 20 MHz sub-channels; 36/160 is centre 50, 157/160 is centre 163, sideband 2.
    EXPECT_EQ(Chanspec::fromString("36/160").centerChannel, 50);
    EXPECT_EQ(Chanspec::fromString("157/160").centerChannel, 163);
    EXPECT_EQ(Chanspec::fromString("157/160").sideband, 2);
    EXPECT_EQ(Chanspec::fromString("157/160").asBroadcomString(), "157/160");
    EXPECT_EQ(Chanspec::fromString("114/160").asString(), "114/160");
    EXPECT_EQ(Chanspec::fromString("50/160").raw, 0xe832);
    for (unsigned c : {36u, 40u, 100u, 124u, 149u, 161u})
    {
        const auto back =
            Chanspec::fromString(Chanspec::fromControlChannel(c, 80)->asBroadcomString());
        EXPECT_EQ(back.controlChannel(), c);
    }
}
