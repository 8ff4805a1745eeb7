/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/Clock.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/Intel5300Format.h>

#include <cmath>

namespace mrpt_wifi::intel5300
{
namespace
{
double dbinv(double x)
{
    return std::pow(10.0, x / 10.0);
}
}  // namespace

double BfeeRecord::totalRss_dBm() const
{
    double mag = 0;
    for (auto r : rssi)
        if (r) mag += dbinv(r);
    return 10.0 * std::log10(mag) - 44.0 - agc;
}

double BfeeRecord::scaleFactor() const
{
    double csiPwr = 0;
    for (size_t i = 0; i < size_t(nTx) * nRx * kSubcarriers; ++i) csiPwr += std::norm(csi[i]);
    if (csiPwr <= 0) return 0.0;
    const double scale = dbinv(totalRss_dBm()) / (csiPwr / kSubcarriers);
    const double thermal = dbinv(noise == -127 ? -92.0 : double(noise));
    const double quant = scale * nRx * nTx;
    double f = std::sqrt(scale / (thermal + quant));
    if (nTx == 2) f *= std::sqrt(2.0);
    if (nTx == 3) f *= std::sqrt(dbinv(4.5));
    return f;
}

bool parseBfee(const uint8_t* d, size_t len, BfeeRecord& r, std::string& why, std::string* reason)
{
    const auto fail = [&](const char* category, std::string text)
    {
        if (reason) *reason = category;
        why = std::move(text);
        return false;
    };
    if (len < kBfeeHeaderBytes)
        return fail(
            "beamforming record shorter than its header",
            "beamforming record of " + std::to_string(len) + " bytes, shorter than its header");
    r = BfeeRecord{};
    r.timestampLow =
        uint32_t(d[0]) | uint32_t(d[1]) << 8 | uint32_t(d[2]) << 16 | uint32_t(d[3]) << 24;
    r.bfeeCount = uint16_t(d[4] | d[5] << 8);
    r.nRx = d[8];
    r.nTx = d[9];
    r.rssi = {d[10], d[11], d[12]};
    r.noise = int8_t(d[13]);
    r.agc = d[14];
    const uint8_t antennaSel = d[15];
    const unsigned payloadLen = unsigned(d[16] | d[17] << 8);
    r.rate = uint16_t(d[18] | d[19] << 8);
    if (r.nRx < 1 || r.nRx > kMaxAntennas || r.nTx < 1 || r.nTx > kMaxAntennas)
        return fail(
            "impossible antenna counts", "Nrx=" + std::to_string(r.nRx) + " Ntx=" +
                                             std::to_string(r.nTx) + " (the 5300 has 1–3)");
    const unsigned nPairs = unsigned(r.nRx) * r.nTx;
    const unsigned calcLen = (kSubcarriers * (nPairs * 8 * 2 + 3) + 7) / 8;
    const size_t held = len - kBfeeHeaderBytes;
    const std::string sizes = "payload field " + std::to_string(payloadLen) + " bytes, record " +
                              std::to_string(held) +
                              " after the header, Nrx=" + std::to_string(r.nRx) +
                              " Ntx=" + std::to_string(r.nTx) + " need " + std::to_string(calcLen);
    if (payloadLen != calcLen || held < calcLen)
        return fail("CSI payload size disagrees with the antenna counts", sizes);
    // The record length must be header + payload exactly, or that plus the WSR Toolbox's
    // trailer: anything else between would be read as CSI.
    const uint8_t* p = d + kBfeeHeaderBytes;
    if (held == calcLen + kWsrExtraBytes)
    {
        const auto u32 = [](const uint8_t* b) {
            return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 |
                   uint32_t(b[3]) << 24;
        };
        WsrTrailer t;
        t.hostTime_s = double(u32(p)) + 1e-6 * double(u32(p + 4));
        std::copy(p + 8, p + 14, t.senderMac.begin());
        t.frameCount = u32(p + 14);
        r.wsr = t;
        p += kWsrExtraBytes;
    }
    else if (held != calcLen)
        return fail("record length disagrees with its header and CSI payload", sizes);
    // read_bfee.c reads one byte past the payload for the last value; treat it as 0.
    const auto byteAt = [&](unsigned i) -> unsigned { return i < calcLen ? p[i] : 0u; };
    std::array<std::complex<float>, kMaxAntennas * kMaxAntennas * kSubcarriers> raw{};
    unsigned index = 0;
    for (unsigned s = 0; s < kSubcarriers; ++s)
    {
        index += 3;
        const unsigned rem = index % 8;
        for (unsigned j = 0; j < nPairs; ++j)
        {
            const auto re =
                int8_t(uint8_t((byteAt(index / 8) >> rem) | (byteAt(index / 8 + 1) << (8 - rem))));
            const auto im = int8_t(
                uint8_t((byteAt(index / 8 + 1) >> rem) | (byteAt(index / 8 + 2) << (8 - rem))));
            // MATLAB array [Ntx, Nrx, 30], column-major: j = tx + Ntx · rx.
            const unsigned tx = j % r.nTx, rx = j / r.nTx;
            raw[(tx * r.nRx + rx) * kSubcarriers + s] = {float(re), float(im)};
            index += 16;
        }
    }
    r.perm = {
        uint8_t(antennaSel & 3), uint8_t((antennaSel >> 2) & 3), uint8_t((antennaSel >> 4) & 3)};
    // read_bf_file applies the permutation only when perm(1:Nrx) sums to 1+..+Nrx.
    unsigned sum = 0;
    for (unsigned i = 0; i < r.nRx; ++i) sum += r.perm[i] + 1u;
    r.permValid = r.nRx > 1 && sum == unsigned(r.nRx) * (unsigned(r.nRx) + 1) / 2;
    r.csi = raw;
    if (r.permValid)
        for (unsigned tx = 0; tx < r.nTx; ++tx)
            for (unsigned rx = 0; rx < r.nRx; ++rx)
                for (unsigned s = 0; s < kSubcarriers; ++s)
                    r.csi[(tx * r.nRx + r.perm[rx]) * kSubcarriers + s] =
                        raw[(tx * r.nRx + rx) * kSubcarriers + s];
    return true;
}

const std::array<int, kSubcarriers>& groupedSubcarriers(bool ht40)
{
    static const std::array<int, kSubcarriers> k20 = {
        -28, -26, -24, -22, -20, -18, -16, -14, -12, -10, -8, -6, -4, -2, -1,
        1,   3,   5,   7,   9,   11,  13,  15,  17,  19,  21, 23, 25, 27, 28};
    static const std::array<int, kSubcarriers> k40 = {
        -58, -54, -50, -46, -42, -38, -34, -30, -26, -22, -18, -14, -10, -6, -2,
        2,   6,   10,  14,  18,  22,  26,  30,  34,  38,  42,  46,  50,  54, 58};
    return ht40 ? k40 : k20;
}

void toObservation(const BfeeRecord& r, const Chanspec& chanspec, CObservationWiFiCSI& obs)
{
    obs.chanspec = chanspec;
    obs.source = r.wsr ? "iwl5300-wsr" : "iwl5300";
    obs.chipId = 0;
    obs.firmwareCounter = r.wsr ? uint16_t(r.wsr->frameCount & 0xFFFF) : r.bfeeCount;
    if (r.wsr)
    {
        std::copy(r.wsr->senderMac.begin(), r.wsr->senderMac.end(), obs.transmitter.bytes.begin());
        obs.timestamp = mrpt::Clock::fromDouble(r.wsr->hostTime_s);
    }
    obs.rssi_dBm = int8_t(std::lround(std::clamp(r.totalRss_dBm(), -128.0, 127.0)));
    obs.antennaRssi_dB.assign(r.rssi.begin(), r.rssi.begin() + r.nRx);
    obs.noiseFloor_dBm = r.noise == -127 ? std::numeric_limits<float>::quiet_NaN() : r.noise;
    obs.agc_dB = r.agc;
    obs.resize(r.nTx, r.nRx, chanspec.nfft());
    const auto& ks = groupedSubcarriers(r.ht40());
    obs.subcarrierIndices.assign(ks.begin(), ks.end());
    for (unsigned tx = 0; tx < r.nTx; ++tx)
        for (unsigned rx = 0; rx < r.nRx; ++rx)
        {
            for (unsigned s = 0; s < kSubcarriers; ++s)
                obs.at(tx, rx, subcarrierToBin(ks[s], obs.nfft())) = r.at(tx, rx, s);
            obs.setPresent(tx, rx);
        }
    obs.scaledCsiFactor = r.scaleFactor();
}

namespace
{
class Intel5300Decoder : public CsiDecoder
{
public:
    std::string name() const override { return "intel5300"; }
    std::string description() const override
    {
        return "Linux 802.11n CSI Tool .dat (Intel 5300): 30 grouped subcarriers, up to 3x3, "
               "20/40 MHz";
    }
    int probe(const uint8_t* head, size_t len) const override
    {
        // Walk the records in the head: every length must fit and a 0xBB record must parse.
        size_t pos = 0;
        bool sawBfee = false;
        while (pos + 3 <= len)
        {
            const size_t fieldLen = size_t(head[pos] << 8 | head[pos + 1]);
            if (fieldLen < 1) return 0;
            const uint8_t code = head[pos + 2];
            if (pos + 2 + fieldLen > len) break;  // record runs past the head: can't tell more
            if (code == kCodeBeamforming)
            {
                BfeeRecord r;
                std::string why;
                // One good record is enough (a bad one after it is the decoder's to report).
                if (parseBfee(head + pos + 3, fieldLen - 1, r, why)) sawBfee = true;
            }
            pos += 2 + fieldLen;
        }
        return sawBfee ? 90 : 0;
    }
    void decodeFile(
        const std::string& path, const CsiDecodeOptions& options, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const override
    {
        const auto bytes = readWholeFile(path);
        ProgressThrottle progress(onProgress);
        if (!options.chanspec)
            summary.notes.push_back(
                "the .dat records carry no channel: assumed 5 GHz channel 36 (20 MHz) / 38 (40 "
                "MHz); give --channel for the true one");
        size_t pos = 0;
        bool sawWsr = false;
        // As read_bf_file: a record needs its 3-byte size + code.
        while (pos + 3 <= bytes.size())
        {
            const size_t fieldLen = size_t(bytes[pos] << 8 | bytes[pos + 1]);
            const uint8_t code = bytes[pos + 2];
            // Without a length the record boundaries are lost: nothing after can be trusted.
            if (fieldLen < 1) throw CsiDecodeError(path, pos, name(), "record of length 0");
            if (pos + 2 + fieldLen > bytes.size() && summary.records == 0)
                throw CsiDecodeError(
                    path, pos, name(),
                    "the first record announces " + std::to_string(fieldLen) +
                        " bytes, the file "
                        "has " +
                        std::to_string(bytes.size() - pos - 2) +
                        " (not an Intel 5300 .dat, or cut inside its first record)");
            if (pos + 2 + fieldLen > bytes.size())
            {
                summary.noteOnce(
                    "the last record (byte " + std::to_string(pos) +
                    ") is truncated: " + std::to_string(fieldLen) + " bytes announced, " +
                    std::to_string(bytes.size() - pos - 2) +
                    " in the file (a capture that was stopped?); ignored");
                break;
            }
            ++summary.records;
            if (code != kCodeBeamforming)
            {
                ++summary.skipped;
                pos += 2 + fieldLen;
                continue;
            }
            BfeeRecord r;
            std::string why, reason;
            if (!parseBfee(bytes.data() + pos + 3, fieldLen - 1, r, why, &reason))
            {
                rejectRecord(path, name(), options, summary, pos, reason, why);
                pos += 2 + fieldLen;
                progress.update(pos, bytes.size());
                continue;
            }
            Chanspec cs = options.chanspec ? *options.chanspec
                                           : Chanspec::make(r.ht40() ? 38 : 36, r.ht40() ? 40 : 20);
            if (cs.bandwidthMHz != (r.ht40() ? 40u : 20u))
                cs = Chanspec::make(r.ht40() ? 38 : 36, r.ht40() ? 40 : 20);
            auto obs = CObservationWiFiCSI::Create();
            obs->sensorLabel = options.assembler.sensorLabel;
            obs->sensorPose = options.assembler.sensorPose;
            obs->routerAddress = "file";
            // The record's clock is the NIC's µs counter, not wall time (a WSR record carries
            // the host's time, set by toObservation).
            obs->timestamp = mrpt::Clock::fromDouble(r.timestampLow * 1e-6);
            toObservation(r, cs, *obs);
            sawWsr = sawWsr || r.wsr.has_value();
            ++summary.frames;
            onFrame(std::move(obs));
            pos += 2 + fieldLen;
            progress.update(pos, bytes.size());
        }
        if (sawWsr)
            summary.notes.push_back(
                "WSR Toolbox records: timestamps from the logging computer's clock, the "
                "transmitter is the sender's MAC, firmwareCounter the low 16 bits of the sender's "
                "frame counter (pairs a packet with its reply)");
        progress.update(1, 1);
    }
};
}  // namespace
}  // namespace mrpt_wifi::intel5300

using mrpt_wifi::intel5300::Intel5300Decoder;
MRPT_WIFI_REGISTER_CSI_DECODER(Intel5300Decoder)
