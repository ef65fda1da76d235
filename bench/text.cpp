#include "text.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common.hpp"

namespace tumble_bench {

std::string fill_placeholders(const std::string& text, const Fields& fields,
                              const std::string& where) {
  std::string out;
  out.reserve(text.size());
  std::size_t pos = 0;
  while (true) {
    const std::size_t open = text.find("{{", pos);
    if (open == std::string::npos) break;
    const std::size_t close = text.find("}}", open + 2);
    if (close == std::string::npos) throw std::runtime_error(where + ": unclosed {{");
    const std::string key = text.substr(open + 2, close - open - 2);
    const auto it = fields.find(key);
    if (it == fields.end()) throw std::runtime_error(where + ": no value for {{" + key + "}}");
    out.append(text, pos, open - pos).append(it->second);
    pos = close + 2;
  }
  return out.append(text, pos, std::string::npos);
}

std::string fill_template(const std::string& name, const Fields& fields) {
  const fs::path path = fs::path(TUMBLE_BENCH_TEXT_DIR) / (name + ".md");
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read the template " + path.string());
  std::ostringstream s;
  s << f.rdbuf();
  return fill_placeholders(s.str(), fields, path.filename().string());
}

std::string bullet_list(const std::vector<std::string>& items) {
  std::string s;
  for (const std::string& i : items) s += "- " + i + ".\n";
  return s;
}

}  // namespace tumble_bench
