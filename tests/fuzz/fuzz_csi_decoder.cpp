// libFuzzer target for one CSI file decoder (MRPT_WIFI_FUZZ_FORMAT: "nexmon", "intel5300",
// "atheros", "esp32"): arbitrary bytes as a whole input file through the decoder the CLIs use. Bad
// input must end in CsiDecodeError / std::runtime_error, never in a crash, leak, UB or a frame
// whose shape disagrees with its data.
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

using namespace mrpt_wifi;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static const std::string path =
        "/tmp/mrpt_wifi_fuzz_" MRPT_WIFI_FUZZ_FORMAT "_" + std::to_string(getpid()) + ".bin";
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) __builtin_trap();
        if (size) std::fwrite(data, 1, size, f);
        std::fclose(f);
    }
    try
    {
        decodeCsiFile(
            path, MRPT_WIFI_FUZZ_FORMAT, {},
            [](CObservationWiFiCSI::Ptr&& o)
            {
                if (o->csi.size() != size_t(o->nTx) * o->nRx * o->nfft()) __builtin_trap();
                for (int k : o->dataSubcarriers())
                    if (k < -int(o->nfft() / 2) || k >= int(o->nfft() / 2)) __builtin_trap();
                (void)o->scaledCsi();
            });
    }
    catch (const std::runtime_error&)
    {
        // CsiDecodeError and the pcap reader's errors: the expected outcome for bad input.
    }
    return 0;
}
