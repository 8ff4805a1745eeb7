#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>
#include <mrpt_wifi/sensor/PcapIO.h>

#include <fstream>

#include "SyntheticCsi.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
/** Hand-made capture files, to test link types and packets the writer never produces. */
struct RawCapture
{
    std::vector<uint8_t> bytes;
    void u16le(uint16_t v) { bytes.insert(bytes.end(), {uint8_t(v), uint8_t(v >> 8)}); }
    void u32le(uint32_t v)
    {
        for (int i = 0; i < 4; ++i) bytes.push_back(uint8_t(v >> (8 * i)));
    }
    void append(const std::vector<uint8_t>& v) { bytes.insert(bytes.end(), v.begin(), v.end()); }
    void save(const std::string& path) const
    {
        std::ofstream(path, std::ios::binary)
            .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    }
};

RawCapture classicPcap(uint32_t linkType)
{
    RawCapture c;
    c.u32le(0xA1B2C3D4);
    c.u16le(2), c.u16le(4);
    c.u32le(0), c.u32le(0), c.u32le(65535), c.u32le(linkType);
    return c;
}

void addRecord(
    RawCapture& c, const std::vector<uint8_t>& frame, uint32_t sec = 1, uint32_t usec = 0)
{
    c.u32le(sec), c.u32le(usec), c.u32le(uint32_t(frame.size())), c.u32le(uint32_t(frame.size()));
    c.append(frame);
}

std::vector<uint8_t> ipv4Udp(
    const std::vector<uint8_t>& payload, uint16_t dport, uint8_t proto = 17)
{
    std::vector<uint8_t> p = {0x45, 0, 0,  0,  0,  0,  0x40, 0,   64,  proto,
                              0,    0, 10, 10, 10, 10, 255,  255, 255, 255};
    const uint16_t total = uint16_t(20 + 8 + payload.size());
    p[2] = uint8_t(total >> 8), p[3] = uint8_t(total);
    const uint16_t ulen = uint16_t(8 + payload.size());
    p.insert(
        p.end(),
        {0x15, 0x7c, uint8_t(dport >> 8), uint8_t(dport), uint8_t(ulen >> 8), uint8_t(ulen), 0, 0});
    p.insert(p.end(), payload.begin(), payload.end());
    return p;
}

std::vector<uint8_t> ethernet(
    const std::vector<uint8_t>& ip, uint16_t ethertype = 0x0800, bool vlan = false)
{
    std::vector<uint8_t> f(12, 0xFF);
    if (vlan) f.insert(f.end(), {0x81, 0x00, 0x00, 0x05});
    f.insert(f.end(), {uint8_t(ethertype >> 8), uint8_t(ethertype)});
    f.insert(f.end(), ip.begin(), ip.end());
    return f;
}

std::vector<uint8_t> oneDatagram()
{
    return nexmon::encodeFrame(*test::syntheticFrame(1, 1, 20))[0];
}
}  // namespace

TEST(PcapIO, WriterReaderRoundTrip)
{
    test::TempDir tmp;
    const auto frame = test::syntheticFrame(4, 4, 80, 42);
    const auto datagrams = nexmon::encodeFrame(*frame);
    const auto t = mrpt::Clock::fromDouble(1700000000.123456);
    {
        PcapWriter w(tmp.file("a.pcap"));
        for (const auto& d : datagrams) w.writeUdp(d.data(), d.size(), t);
        EXPECT_EQ(w.packetsWritten(), 16u);
    }
    PcapReader r(tmp.file("a.pcap"));
    EXPECT_EQ(r.linkTypeName(), "EN10MB");
    PcapUdpDatagram d;
    size_t n = 0;
    while (r.next(d))
    {
        ASSERT_LT(n, datagrams.size());
        EXPECT_EQ(std::vector<uint8_t>(d.payload, d.payload + d.payloadLength), datagrams[n]);
        EXPECT_EQ(d.sourceAddress, "10.10.10.10");
        EXPECT_EQ(d.destinationPort, 5500);
        EXPECT_NEAR(mrpt::Clock::toDouble(d.timestamp), 1700000000.123456, 2e-6);
        ++n;
    }
    EXPECT_EQ(n, 16u);
    EXPECT_EQ(r.position(), r.fileSize());
}

TEST(PcapIO, SkipsAndCountsWhatIsNotCsi)
{
    test::TempDir tmp;
    auto c = classicPcap(1);
    const auto d = oneDatagram();
    addRecord(c, ethernet({0, 1, 8, 0, 6, 4, 0, 1}, 0x0806));  // ARP
    addRecord(c, ethernet(ipv4Udp(d, 5500, 6)));               // TCP
    addRecord(c, ethernet(ipv4Udp(d, 53)));                    // DNS
    addRecord(c, ethernet(ipv4Udp(d, 5500), 0x0800, true));    // 802.1Q tagged CSI
    addRecord(c, ethernet(ipv4Udp(d, 5500)));                  // plain CSI
    c.save(tmp.file("mixed.pcap"));

    PcapReader r(tmp.file("mixed.pcap"));
    PcapUdpDatagram out;
    int n = 0;
    while (r.next(out))
    {
        EXPECT_EQ(std::vector<uint8_t>(out.payload, out.payload + out.payloadLength), d);
        ++n;
    }
    EXPECT_EQ(n, 2);
    EXPECT_EQ(r.stats().skippedNotIp, 1u);
    EXPECT_EQ(r.stats().skippedNotUdp, 1u);
    EXPECT_EQ(r.stats().skippedOtherPort, 1u);
    EXPECT_EQ(r.stats().packets, 5u);
}

TEST(PcapIO, LinuxCookedLinkTypes)
{
    test::TempDir tmp;
    const auto d = oneDatagram();
    auto sll = classicPcap(113);
    std::vector<uint8_t> f = {0, 0, 0, 1, 0, 6, 1, 2, 3, 4, 5, 6, 0, 0, 0x08, 0x00};
    const auto ip = ipv4Udp(d, 5500);
    f.insert(f.end(), ip.begin(), ip.end());
    addRecord(sll, f);
    sll.save(tmp.file("sll.pcap"));

    auto sll2 = classicPcap(276);
    std::vector<uint8_t> g = {0x08, 0x00, 0, 0, 0, 0, 0, 2, 0, 1, 0, 6, 1, 2, 3, 4, 5, 6, 0, 0};
    g.insert(g.end(), ip.begin(), ip.end());
    addRecord(sll2, g);
    sll2.save(tmp.file("sll2.pcap"));

    for (const char* name : {"sll.pcap", "sll2.pcap"})
    {
        PcapReader r(tmp.file(name));
        PcapUdpDatagram out;
        ASSERT_TRUE(r.next(out)) << name;
        EXPECT_EQ(out.payloadLength, d.size()) << name;
        EXPECT_FALSE(r.next(out));
    }
}

TEST(PcapIO, ReadsPcapng)
{
    test::TempDir tmp;
    const auto frame = ethernet(ipv4Udp(oneDatagram(), 5500));
    RawCapture c;
    // Section header block, interface description block (Ethernet), one enhanced packet block.
    c.u32le(0x0A0D0D0A), c.u32le(28), c.u32le(0x1A2B3C4D), c.u16le(1), c.u16le(0);
    c.u32le(0xFFFFFFFF), c.u32le(0xFFFFFFFF), c.u32le(28);
    c.u32le(1), c.u32le(20), c.u16le(1), c.u16le(0), c.u32le(65535), c.u32le(20);
    const uint32_t padded = uint32_t((frame.size() + 3) / 4 * 4);
    c.u32le(6), c.u32le(32 + padded), c.u32le(0), c.u32le(0), c.u32le(1000000);
    c.u32le(uint32_t(frame.size())), c.u32le(uint32_t(frame.size()));
    c.append(frame);
    c.bytes.resize(c.bytes.size() + (padded - frame.size()), 0);
    c.u32le(32 + padded);
    c.save(tmp.file("a.pcapng"));
    EXPECT_EQ(detectCsiFileKind(tmp.file("a.pcapng")), CsiFileKind::Pcap);
    PcapReader r(tmp.file("a.pcapng"));
    PcapUdpDatagram out;
    ASSERT_TRUE(r.next(out));
    EXPECT_EQ(out.payloadLength, oneDatagram().size());
    EXPECT_NEAR(mrpt::Clock::toDouble(out.timestamp), 1.0, 1e-6);
}

TEST(PcapIO, BadFilesNameTheFileAndOffset)
{
    test::TempDir tmp;
    EXPECT_THROW(PcapReader(tmp.file("missing.pcap")), std::runtime_error);

    std::ofstream(tmp.file("text.pcap")) << "this is not a capture at all\n";
    try
    {
        PcapReader r(tmp.file("text.pcap"));
        FAIL() << "accepted a text file";
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find("text.pcap"), std::string::npos) << e.what();
    }

    // A capture cut in the middle of its third record.
    {
        PcapWriter w(tmp.file("full.pcap"));
        const auto d = oneDatagram();
        for (int i = 0; i < 3; ++i)
            w.writeUdp(d.data(), d.size(), mrpt::Clock::fromDouble(1.0 + i));
    }
    const auto full = test::readFile(tmp.file("full.pcap"));
    const size_t recordSize = (full.size() - 24) / 3;
    std::ofstream(tmp.file("cut.pcap"), std::ios::binary)
        .write(full.data(), std::streamsize(24 + 2 * recordSize + 30));
    // A capture that was stopped: the records before are read, the cut one is reported as the
    // file's truncated tail (not an error).
    PcapReader r(tmp.file("cut.pcap"));
    PcapUdpDatagram out;
    EXPECT_TRUE(r.next(out));
    EXPECT_TRUE(r.next(out));
    EXPECT_FALSE(r.next(out));
    EXPECT_TRUE(r.stats().truncatedTail);
    EXPECT_EQ(r.stats().truncatedTailOffset, 24 + 2 * recordSize);
    // A record whose header is impossible (caplen > snaplen) is an error naming file and offset.
    std::string bogus = full;
    const size_t rec2 = 24 + recordSize;
    bogus[rec2 + 8] = char(0xFF), bogus[rec2 + 9] = char(0xFF), bogus[rec2 + 10] = char(0xFF);
    std::ofstream(tmp.file("bogus.pcap"), std::ios::binary)
        .write(bogus.data(), std::streamsize(bogus.size()));
    PcapReader rb(tmp.file("bogus.pcap"));
    EXPECT_TRUE(rb.next(out));
    try
    {
        rb.next(out);
        FAIL() << "impossible record not reported";
    }
    catch (const std::runtime_error& e)
    {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("bogus.pcap"), std::string::npos) << msg;
        EXPECT_NE(msg.find("byte offset " + std::to_string(rec2)), std::string::npos) << msg;
    }
}

TEST(CsiFileReader, ReadsUpToATruncatedLastRecord)
{
    test::TempDir tmp;
    {
        PcapWriter w(tmp.file("full.pcap"));
        for (uint16_t seq = 0; seq < 3; ++seq)
            for (const auto& d : nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, seq)))
                w.writeUdp(d.data(), d.size(), mrpt::Clock::fromDouble(1.0 + seq * 0.01));
    }
    const auto full = test::readFile(tmp.file("full.pcap"));
    // Cut inside the last datagram of frame 2: frames 0 and 1 complete, frame 2 has 15 pairs.
    std::ofstream(tmp.file("cut.pcap"), std::ios::binary)
        .write(full.data(), std::streamsize(full.size() - 100));
    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiFileReadSummary summary;
    readCsiFrames(
        tmp.file("cut.pcap"), {}, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); }, {},
        &summary);
    EXPECT_TRUE(summary.pcap.truncatedTail);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_TRUE(frames[0]->isComplete());
    EXPECT_TRUE(frames[1]->isComplete());
    EXPECT_EQ(frames[2]->presentPairs(), 15u);
    EXPECT_EQ(summary.frames, 3u);
    EXPECT_EQ(summary.assembler.framesIncomplete, 1u);
}
