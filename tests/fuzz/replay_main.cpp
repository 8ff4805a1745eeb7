// Replays inputs through a libFuzzer target without libFuzzer (any compiler): every file named
// on the command line is one input. Reproduces a crash a fuzzer found; in normal builds it also
// keeps the fuzz targets compiling with gcc.
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv)
{
    for (int i = 1; i < argc; ++i)
    {
        std::ifstream in(argv[i], std::ios::binary);
        if (!in)
        {
            std::fprintf(stderr, "cannot open '%s'\n", argv[i]);
            return 1;
        }
        const std::vector<uint8_t> bytes(
            (std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
        std::printf("%s: ok (%zu bytes)\n", argv[i], bytes.size());
    }
    return 0;
}
