// libFuzzer target for one CSI file decoder (MRPT_WIFI_FUZZ_FORMAT: "nexmon", "intel5300",
// "atheros", "esp32"): arbitrary bytes as a whole input file through the decoder the CLIs use. Bad
// input must end in CsiDecodeError / std::runtime_error, never in a crash, leak, UB or a frame
// whose shape disagrees with its data.
//
// The Nexmon decoder reads anything that is not a capture as a rawlog, through MRPT's class
// registry: fuzzing that would fuzz every MRPT class, whose readers allocate whatever a damaged
// count claims (up to 4 GB for a string; ASan's operator new aborts instead of throwing). So a
// non-capture input is read here as a stream of this project's CObservationWiFiCSI only, with
// the same archive and checks as the rawlog reader; other classes are refused by name before
// any of their bytes are read.
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

using namespace mrpt_wifi;

namespace
{
void checkFrame(const CObservationWiFiCSI& o)
{
    if (o.csi.size() != size_t(o.nTx) * o.nRx * o.nfft()) __builtin_trap();
    for (int k : o.dataSubcarriers())
        if (k < -int(o.nfft() / 2) || k >= int(o.nfft() / 2)) __builtin_trap();
    (void)o.scaledCsi();
}

void readStoredFrames(const uint8_t* data, size_t size)
{
    mrpt::io::CMemoryStream stream;
    stream.assignMemoryNotOwn(data, size);
    auto archive = mrpt::serialization::archiveFrom(stream);
    try
    {
        while (stream.getPosition() < size)
        {
            CObservationWiFiCSI frame;
            archive.ReadObject(&frame);
            checkFrame(frame);
        }
    }
    catch (const std::exception&)
    {
        // Damaged or foreign objects: MRPT's and this class' errors are the expected outcome.
    }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (std::string(MRPT_WIFI_FUZZ_FORMAT) == "nexmon" && size >= 4 && !isCaptureMagic(data))
    {
        readStoredFrames(data, size);
        return 0;
    }
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
            path, MRPT_WIFI_FUZZ_FORMAT, {}, [](CObservationWiFiCSI::Ptr&& o) { checkFrame(*o); });
    }
    catch (const std::runtime_error&)
    {
        // CsiDecodeError and the pcap reader's errors: the expected outcome for bad input.
    }
    return 0;
}
