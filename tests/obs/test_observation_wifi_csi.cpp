#include <gtest/gtest.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/ChainStates.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;

namespace
{
CObservationWiFiCSI::Ptr makeFilledObservation()
{
    auto o = CObservationWiFiCSI::Create();
    o->timestamp = mrpt::Clock::fromDouble(1487031139.535287);
    o->sensorLabel = "CSI_FRONT";
    o->sensorPose = mrpt::poses::CPose3D(0.1, -0.2, 0.3, 0.4, -0.05, 0.06);
    o->transmitter = MacAddress::fromString("00:12:34:56:78:9b");
    o->rssi_dBm = -57;
    o->sequenceNumber = 4095;
    o->fragmentNumber = 3;
    o->frameControl = 0x88;
    o->chanspec = Chanspec::make(155, 80, 2);
    o->chipId = 0x006a;
    o->firmwareCounter = 7;
    o->headerVariant = NexmonHeaderVariant::Nexmon;
    o->routerAddress = "10.10.10.10";
    o->resize(2, 4, 256);
    for (unsigned tx = 0; tx < 2; ++tx)
        for (unsigned rx = 0; rx < 4; ++rx)
        {
            if (tx == 1 && rx == 2) continue;  // one pair missing
            o->setPresent(tx, rx);
            for (unsigned b = 0; b < 256; ++b)
                o->at(tx, rx, b) = {
                    float(tx + 1) * std::cos(0.05f * b + rx), -std::sin(0.03f * b) * 0.5f};
        }
    o->maskedBins = {128, 129};
    o->chainDelay_ns = {0.0f, 3.02f, std::nanf(""), -2.9f};
    o->chainState = {0, 1, kUnknownChainState, 2};
    return o;
}

std::vector<uint8_t> serialized(const CObservationWiFiCSI& o)
{
    mrpt::io::CMemoryStream buf;
    auto out = mrpt::serialization::archiveFrom(buf);
    out << o;
    const auto* p = static_cast<const uint8_t*>(buf.getRawBufferData());
    return {p, p + buf.getTotalBytesCount()};
}

mrpt::serialization::CSerializable::Ptr deserialized(const std::vector<uint8_t>& bytes)
{
    mrpt::io::CMemoryStream buf;
    buf.assignMemoryNotOwn(bytes.data(), bytes.size());
    auto in = mrpt::serialization::archiveFrom(buf);
    return in.ReadObject();
}

size_t find(const std::vector<uint8_t>& bytes, const std::string& what)
{
    const auto it = std::search(bytes.begin(), bytes.end(), what.begin(), what.end());
    return it == bytes.end() ? std::string::npos : size_t(it - bytes.begin());
}
}  // namespace

TEST(CObservationWiFiCSI, SerializationRoundTripKeepsEveryField)
{
    const auto a = makeFilledObservation();
    mrpt::io::CMemoryStream buf;
    auto out = mrpt::serialization::archiveFrom(buf);
    out << *a;
    buf.Seek(0);
    auto in = mrpt::serialization::archiveFrom(buf);
    // Read back through MRPT's class registry, as rawlog-edit does.
    const auto obj = in.ReadObject();
    const auto b = std::dynamic_pointer_cast<CObservationWiFiCSI>(obj);
    ASSERT_TRUE(b);
    EXPECT_EQ(b->timestamp, a->timestamp);
    EXPECT_EQ(b->sensorLabel, a->sensorLabel);
    EXPECT_EQ(b->sensorPose, a->sensorPose);
    EXPECT_EQ(b->transmitter, a->transmitter);
    EXPECT_EQ(b->rssi_dBm, a->rssi_dBm);
    EXPECT_EQ(b->sequenceNumber, a->sequenceNumber);
    EXPECT_EQ(b->fragmentNumber, a->fragmentNumber);
    EXPECT_EQ(b->frameControl, a->frameControl);
    EXPECT_EQ(b->chanspec, a->chanspec);
    EXPECT_EQ(b->chanspec.sideband, 2);
    EXPECT_EQ(b->chipId, a->chipId);
    EXPECT_EQ(b->firmwareCounter, a->firmwareCounter);
    EXPECT_EQ(b->headerVariant, a->headerVariant);
    EXPECT_EQ(b->routerAddress, a->routerAddress);
    EXPECT_EQ(b->nRx, 4);
    EXPECT_EQ(b->nTx, 2);
    EXPECT_EQ(b->presentMask, a->presentMask);
    EXPECT_EQ(b->presentPairs(), 7u);
    EXPECT_FALSE(b->isPresent(1, 2));
    EXPECT_EQ(b->maskedBins, a->maskedBins);
    EXPECT_EQ(b->csi, a->csi);
    ASSERT_EQ(b->chainDelay_ns.size(), 4u);
    EXPECT_FLOAT_EQ(b->chainDelay_ns[1], 3.02f);
    EXPECT_TRUE(std::isnan(b->chainDelay_ns[2]));
    EXPECT_EQ(b->chainState, a->chainState);
}

TEST(CObservationWiFiCSI, Version1RawlogsStillLoadWithoutChainStates)
{
    // A version-1 object is a version-3 one without the two chain-state vectors and the
    // receive cores (three empty vectors: 12 bytes of counts before MRPT's end marker) and
    // with version byte 1.
    auto a = makeFilledObservation();
    a->chainDelay_ns.clear();
    a->chainState.clear();
    auto bytes = serialized(*a);
    const std::string name = "CObservationWiFiCSI";
    const size_t at = find(bytes, name);
    ASSERT_NE(at, std::string::npos);
    uint8_t& version = bytes[at + name.size()];
    ASSERT_EQ(version, 3);
    version = 1;
    ASSERT_GE(bytes.size(), 13u);
    const auto end = bytes.end() - 1;  // MRPT's end-of-object marker
    ASSERT_TRUE(std::all_of(end - 12, end, [](uint8_t c) { return c == 0; }));
    bytes.erase(end - 12, end);

    const auto b = std::dynamic_pointer_cast<CObservationWiFiCSI>(deserialized(bytes));
    ASSERT_TRUE(b);
    EXPECT_EQ(b->csi, a->csi);
    EXPECT_TRUE(b->chainDelay_ns.empty());
    EXPECT_TRUE(b->chainState.empty());
}

TEST(CObservationWiFiCSI, DamagedLengthIsAnErrorNotAHugeAllocation)
{
    // A fuzzer found this: a rawlog whose label length reads 0xfffffff0 made MRPT's string
    // reader ask for 4 GB. The bounded reader refuses it and names the field's owner.
    const auto a = makeFilledObservation();
    for (const std::string& field : {a->sensorLabel, a->routerAddress})
    {
        auto bytes = serialized(*a);
        const size_t at = find(bytes, field);
        ASSERT_NE(at, std::string::npos);
        ASSERT_GE(at, 4u);
        const uint32_t huge = 0xfffffff0u;
        std::memcpy(&bytes[at - 4], &huge, 4);
        try
        {
            deserialized(bytes);
            ADD_FAILURE() << "a damaged length of " << field << " was accepted";
        }
        catch (const std::exception& e)
        {
            const std::string msg = e.what();
            EXPECT_NE(msg.find("CObservationWiFiCSI"), std::string::npos) << msg;
            EXPECT_NE(msg.find("exceeds the limit"), std::string::npos) << msg;
        }
    }
}

TEST(CObservationWiFiCSI, CorruptStoredShapeIsAnError)
{
    auto a = makeFilledObservation();
    a->nRx = 3;  // no longer matches the CSI size
    mrpt::io::CMemoryStream buf;
    auto out = mrpt::serialization::archiveFrom(buf);
    out << *a;
    buf.Seek(0);
    auto in = mrpt::serialization::archiveFrom(buf);
    EXPECT_THROW(in.ReadObject(), std::exception);
}

TEST(CObservationWiFiCSI, DataSubcarrierAccessors)
{
    const auto o = makeFilledObservation();
    const auto h = o->dataSubcarrierCsi(0, 1);
    ASSERT_EQ(h.size(), 234u);
    EXPECT_EQ(h.front(), o->at(0, 1, subcarrierToBin(-122, 256)));
    EXPECT_EQ(h.back(), o->at(0, 1, subcarrierToBin(122, 256)));
    const auto f = o->dataSubcarrierFrequencies();
    ASSERT_EQ(f.size(), 234u);
    EXPECT_DOUBLE_EQ(f.front(), 5775e6 - 122 * 312.5e3);
}

TEST(CObservationWiFiCSI, DescriptionNamesWhatAPersonNeeds)
{
    const auto o = makeFilledObservation();
    std::ostringstream s;
    o->getDescriptionAsText(s);
    const std::string d = s.str();
    for (const char* expected :
         {"00:12:34:56:78:9b", "-57 dBm", "channel 155 / 80 MHz", "5775.0 MHz", "0x006a / nexmon",
          "2 tx x 4 rx x 256 bins", "7/8 pairs present", "tx 1 rx 2: MISSING", "tx 0 rx 0:",
          "chain 1 state 1 (+3.02 ns)", "chain 2 state ?", "chain 3 state 2 (-2.90 ns)"})
        EXPECT_NE(d.find(expected), std::string::npos) << "missing '" << expected << "' in\n" << d;
}

TEST(CObservationWiFiCSI, DescriptionSaysWhenTheHeaderHasNoRssi)
{
    auto o = makeFilledObservation();
    o->headerVariant = NexmonHeaderVariant::UbiLocate;
    std::ostringstream s;
    o->getDescriptionAsText(s);
    EXPECT_NE(s.str().find("not reported by the ubilocate header"), std::string::npos) << s.str();
    EXPECT_NE(s.str().find("firmware counter 7"), std::string::npos) << s.str();
}

TEST(CObservationWiFiCSI, DescriptionPhaseSlopeGivesThePathDelay)
{
    // A single path of delay tau: H(k) = exp(-j 2 pi k df tau); the description reports tau.
    auto o = CObservationWiFiCSI::Create();
    o->chanspec = Chanspec::make(42, 80);
    o->resize(1, 1, 256);
    o->setPresent(0, 0);
    const double tau = 50e-9;
    for (int k = -128; k < 128; ++k)
        o->at(0, 0, subcarrierToBin(k, 256)) =
            std::polar(1.0f, float(-2 * M_PI * k * kSubcarrierSpacingHz * tau));
    std::ostringstream s;
    o->getDescriptionAsText(s);
    EXPECT_NE(s.str().find("(50.0 ns)"), std::string::npos) << s.str();
}

TEST(CObservationWiFiCSI, ExportTxtRowHasOneColumnPerValue)
{
    const auto o = makeFilledObservation();
    ASSERT_TRUE(o->exportTxtSupported());
    std::istringstream row(o->exportTxtDataRow());
    std::vector<std::string> cols;
    for (std::string c; row >> c;) cols.push_back(c);
    ASSERT_EQ(cols.size(), 9u + 2u * 4u * 234u * 2u);
    EXPECT_EQ(cols[0], "4095");
    EXPECT_EQ(cols[1], "-57");
    EXPECT_EQ(cols[2], "155");
    // The missing pair (tx 1, rx 2) exports as NaN.
    const size_t missingStart = 9 + (1 * 4 + 2) * 234 * 2;
    EXPECT_EQ(cols[missingStart], "NaN");
    EXPECT_NE(cols[9], "NaN");
}

TEST(CObservationWiFiCSI, ReceiveCoresRoundTripAndVersion2LoadsWithoutThem)
{
    // A router with core mask 0xb: three rows holding cores 0, 1, 3.
    auto a = test::syntheticFrame(1, 3, 20, 5);
    a->rxCores = {0, 1, 3};
    auto bytes = serialized(*a);
    auto b = std::dynamic_pointer_cast<CObservationWiFiCSI>(deserialized(bytes));
    ASSERT_TRUE(b);
    EXPECT_EQ(b->rxCores, a->rxCores);
    EXPECT_EQ(b->rowOfCore(3), 2);
    EXPECT_EQ(b->rowOfCore(2), -1);
    EXPECT_EQ(b->coreOfRow(2), 3u);
    EXPECT_EQ(b->rowCoresAsString(), "0, 1, 3");

    // Version 2 (no receive-core list): rows are cores 0..n-1.
    a->rxCores.clear();
    bytes = serialized(*a);
    const std::string name = "CObservationWiFiCSI";
    const size_t at = find(bytes, name);
    ASSERT_NE(at, std::string::npos);
    bytes[at + name.size()] = 2;
    const auto end = bytes.end() - 1;
    bytes.erase(end - 4, end);
    b = std::dynamic_pointer_cast<CObservationWiFiCSI>(deserialized(bytes));
    ASSERT_TRUE(b);
    EXPECT_TRUE(b->rxCores.empty());
    EXPECT_EQ(b->rowOfCore(2), 2);

    // A damaged list (not ascending) is refused, naming the class.
    a->rxCores = {0, 3, 1};
    EXPECT_THROW(deserialized(serialized(*a)), std::exception);
}
