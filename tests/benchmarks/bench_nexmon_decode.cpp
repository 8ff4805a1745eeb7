// Decode + assembly throughput of 80 MHz 4x4 Nexmon frames on one core.
// Target (foundation issue): >= 1,000,000 datagrams/s.
//   build/bin/bench_nexmon_decode --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;

namespace
{
/** 64 distinct frames' datagrams, replayed with increasing sequence numbers. */
std::vector<std::vector<uint8_t>> makeDatagrams(unsigned nTx, unsigned bandwidthMHz)
{
    std::vector<std::vector<uint8_t>> all;
    for (uint16_t seq = 0; seq < 64; ++seq)
        for (auto& d : nexmon::encodeFrame(*test::syntheticFrame(nTx, 4, bandwidthMHz, seq)))
            all.push_back(std::move(d));
    return all;
}

void setSequence(std::vector<uint8_t>& d, uint16_t seq)
{
    const uint16_t sc = uint16_t(seq << 4);
    d[10] = uint8_t(sc), d[11] = uint8_t(sc >> 8);
}

void BM_DecodeAndAssemble(benchmark::State& state)
{
    const unsigned nTx = unsigned(state.range(0)), bw = unsigned(state.range(1));
    auto datagrams = makeDatagrams(nTx, bw);
    const size_t perFrame = 4 * nTx;
    CsiFrameAssemblerOptions options;
    uint64_t frames = 0;
    CsiFrameAssembler assembler(
        options,
        [&](CObservationWiFiCSI::Ptr&& f)
        {
            benchmark::DoNotOptimize(f->csi.data());
            ++frames;
        });
    const auto t = mrpt::Clock::fromDouble(1.0);
    uint16_t seq = 0;
    size_t bytes = 0, count = 0;
    for (auto _ : state)
    {
        // One pass = 64 frames; renumber so the assembler sees fresh frames every pass.
        for (size_t i = 0; i < datagrams.size(); ++i)
        {
            if (i % perFrame == 0) ++seq;
            setSequence(datagrams[i], uint16_t(seq & 0xFFF));
            assembler.push(datagrams[i].data(), datagrams[i].size(), t);
            bytes += datagrams[i].size();
        }
        count += datagrams.size();
    }
    state.SetItemsProcessed(int64_t(count));
    state.SetBytesProcessed(int64_t(bytes));
    state.counters["datagrams/s"] = benchmark::Counter(double(count), benchmark::Counter::kIsRate);
    state.counters["frames/s"] = benchmark::Counter(double(frames), benchmark::Counter::kIsRate);
    if (assembler.stats().framesIncomplete)
        state.SkipWithError("incomplete frames: benchmark input is wrong");
}
BENCHMARK(BM_DecodeAndAssemble)
    ->Args({4, 80})
    ->Args({1, 80})
    ->Args({4, 20})
    ->Unit(benchmark::kMicrosecond);

void BM_DecodeWordsOnly(benchmark::State& state)
{
    const auto d = makeDatagrams(1, 80).front();
    std::vector<std::complex<float>> out(256);
    for (auto _ : state)
    {
        nexmon::decodeWords(d.data() + nexmon::csiOffset(), 256, out.data());
        benchmark::DoNotOptimize(out.data());
    }
    state.counters["datagrams/s"] =
        benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DecodeWordsOnly);
}  // namespace

BENCHMARK_MAIN();
