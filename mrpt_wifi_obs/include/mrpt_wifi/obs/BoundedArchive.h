/* mrpt_wifi — WiFi channel state information for MRPT.
 * Reading of length-prefixed fields with a bound, for files that may be damaged. */
#pragma once

#include <mrpt/core/exceptions.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** Longest string any of this project's objects stores (labels, names, SSIDs). */
constexpr uint32_t kMaxStoredStringLength = 1u << 16;

/** Reads a string written by MRPT's `operator<<(CArchive&, const std::string&)` (a uint32
 * length, then the bytes), refusing a length above `maxLength`.
 *
 * Why: MRPT's own reader resizes the string to whatever length the file claims before it
 * reads a byte, so one damaged length in a rawlog asks for up to 4 GB. */
inline void readBoundedString(
    mrpt::serialization::CArchive& in, std::string& s, uint32_t maxLength, const char* what)
{
    const auto n = in.ReadAs<uint32_t>();
    if (n > maxLength)
        THROW_EXCEPTION_FMT(
            "%s: stored length %u exceeds the limit of %u (damaged file?)", what, n, maxLength);
    s.resize(n);
    if (n > 0) in.ReadBuffer(s.data(), n);
}

/** Reads a vector of arithmetic values written by MRPT's `operator<<` for std::vector (a
 * uint32 count, then the values), refusing a count above `maxCount`. */
template <typename T>
void readBoundedVector(
    mrpt::serialization::CArchive& in, std::vector<T>& v, uint32_t maxCount, const char* what)
{
    static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>);
    const auto n = in.ReadAs<uint32_t>();
    if (n > maxCount)
        THROW_EXCEPTION_FMT(
            "%s: stored count %u exceeds the limit of %u (damaged file?)", what, n, maxCount);
    v.resize(n);
    if (n > 0) in.ReadBufferFixEndianness(v.data(), n);
}

}  // namespace mrpt_wifi
