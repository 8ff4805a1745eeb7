/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/emulator/ToolResult.h>

#include <cerrno>
#include <cstdlib>

namespace mrpt_wifi::emulator
{
ShortOptionParser::ShortOptionParser(const Argv& args, std::string spec)
    : args_(args), spec_(std::move(spec))
{
}

bool ShortOptionParser::next(char& option, std::string& value)
{
    value.clear();
    if (charPos_ == 0)
    {
        if (index_ >= args_.size()) return false;
        const std::string& a = args_[index_];
        if (a == "--")
        {
            ++index_;
            return false;
        }
        if (a.size() < 2 || a[0] != '-') return false;  // first operand: options end here
        charPos_ = 1;
    }
    const std::string& a = args_[index_];
    option = a[charPos_++];
    const auto where = spec_.find(option);
    if (option == ':' || where == std::string::npos)
    {
        error_ = std::string("invalid option -- '") + option + "'";
        return false;
    }
    const bool takesValue = where + 1 < spec_.size() && spec_[where + 1] == ':';
    if (takesValue)
    {
        if (charPos_ < a.size())
            value = a.substr(charPos_);  // "-l34"
        else if (index_ + 1 < args_.size())
            value = args_[++index_];  // "-l 34"
        else
        {
            error_ = std::string("option requires an argument -- '") + option + "'";
            return false;
        }
        charPos_ = 0;
        ++index_;
    }
    else if (charPos_ >= a.size())
    {
        charPos_ = 0;
        ++index_;
    }
    return true;
}

Argv ShortOptionParser::remaining() const
{
    return Argv(args_.begin() + long(std::min(index_, args_.size())), args_.end());
}

bool parseUnsigned(const std::string& text, unsigned long max, unsigned long& out)
{
    if (text.empty() || text[0] == '-' || text[0] == '+' || text[0] == ' ') return false;
    errno = 0;
    char* end = nullptr;
    const unsigned long v = std::strtoul(text.c_str(), &end, 0);
    if (errno != 0 || *end != '\0' || v > max) return false;
    out = v;
    return true;
}

}  // namespace mrpt_wifi::emulator
