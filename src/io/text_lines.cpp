#include "io/text_lines.h"

#include "core/types.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <sstream>

namespace vkmesh::io::text {

namespace fs = std::filesystem;

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

std::string fmt(double v) {
    std::ostringstream os;
    os.precision(10);
    os << v;
    return os.str();
}

std::string fmtFixed(double v, int decimals) {
    std::ostringstream os;
    os << std::fixed;
    os.precision(decimals);
    os << v;
    return os.str();
}

std::string fmtTime(double t) {
    if (t == std::floor(t) && std::abs(t) < 1e15) return std::to_string(static_cast<long long>(t));
    std::string s = fmtFixed(t, 6);
    while (s.back() == '0') s.pop_back();
    return s;
}

std::string at(const fs::path& file, size_t line) { return file.string() + ":" + std::to_string(line); }
std::string at(const std::string& source, size_t line) { return source + ":" + std::to_string(line); }

std::vector<std::string> splitWhitespace(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream is(line);
    for (std::string tok; is >> tok;) out.push_back(tok);
    return out;
}

std::string joined(const std::vector<std::string>& tokens) {
    std::string s;
    for (const auto& t : tokens) s += (s.empty() ? "" : " ") + t;
    return s;
}

bool parseNumber(std::string_view tok, double& out) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);  // from_chars refuses a leading '+'
    if (tok.empty()) return false;
    auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
    return ec == std::errc() && end == tok.data() + tok.size();
}

bool parseInteger(std::string_view tok, long long& out) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    if (tok.empty()) return false;
    auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
    return ec == std::errc() && end == tok.data() + tok.size();
}

std::vector<TextLine> readDataLines(std::istream& in, const std::string& source) {
    std::vector<TextLine> out;
    std::string line;
    for (size_t n = 1; std::getline(in, line); ++n) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        out.push_back({n, splitWhitespace(line)});
    }
    if (in.bad()) throw Error("error while reading " + source);
    return out;
}

std::ifstream openText(const fs::path& file) {
    std::ifstream in(file);
    if (!in) throw Error("cannot open " + file.string());
    return in;
}

}  // namespace vkmesh::io::text
