// libFuzzer target: arbitrary bytes as a stream of datagrams through the Nexmon parser and the
// frame assembler. Input: byte 0 picks the header format and bin policy, then records of
// [uint16 little-endian length][payload]. Any crash, leak, UB or escaping exception is a bug.
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>

#include <cstddef>
#include <cstdint>

using namespace mrpt_wifi;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1) return 0;
    CsiFrameAssemblerOptions options;
    options.format = nexmon::FormatHint(data[0] & 3);
    options.overwrittenBins = OverwrittenBinPolicy((data[0] >> 2) % 3);
    options.maxPendingTransmitters = 8;
    options.frameTimeout_s = 0.01;
    uint64_t frames = 0;
    CsiFrameAssembler assembler(
        options,
        [&](CObservationWiFiCSI::Ptr&& f)
        {
            // Touch everything a consumer would.
            if (f->csi.size() != size_t(f->nTx) * f->nRx * f->nfft()) __builtin_trap();
            ++frames;
        });
    auto t = mrpt::Clock::fromDouble(1.0);
    size_t pos = 1;
    while (pos + 2 <= size)
    {
        const size_t len = size_t(data[pos]) | size_t(data[pos + 1]) << 8;
        pos += 2;
        const size_t n = std::min(len, size - pos);
        assembler.push(data + pos, n, t, "fuzz");
        pos += n;
        t += std::chrono::milliseconds(3);
        assembler.flushExpired(t);
    }
    assembler.flushAll();
    return 0;
}
