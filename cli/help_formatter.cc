// --help without CLI11's type artefacts: "--seed SEED  ... (default: 0)" instead of
// "--seed TEXT=0", "--no-peers" instead of "--no-peers{false}".
#include <cctype>
#include <sstream>

#include "cli/common.h"

namespace fetchscope::cli {
namespace {

class HelpFormatter : public CLI::Formatter {
 public:
  // names without the default flag values CLI11 appends ("{false}")
  std::string make_option_name(const CLI::Option* opt, bool is_positional) const override {
    if (is_positional) return opt->get_name(true, false);
    return opt->get_name(false, false);
  }

  // a placeholder named after the option (argparse style: --json-out JSON_OUT), "..." for
  // lists; no type names, ranges or defaults (the default goes into the description)
  std::string make_option_opts(const CLI::Option* opt) const override {
    if (!opt->get_option_text().empty()) return " " + opt->get_option_text();
    if (IsFlag(opt)) return "";
    std::ostringstream out;
    out << " " << Placeholder(opt);
    if (opt->get_expected_max() == CLI::detail::expected_max_vector_size) out << " ...";
    return out.str();
  }

  std::string make_option_desc(const CLI::Option* opt) const override {
    std::string desc = opt->get_description();
    if (!IsFlag(opt) && !opt->get_default_str().empty()) {
      desc += " (default: " + opt->get_default_str() + ")";
    }
    if (opt->get_required()) desc += " (required)";
    if (!opt->get_envname().empty()) desc += " (environment: " + opt->get_envname() + ")";
    return desc;
  }

 private:
  // flags take no value (CLI11 gives them expected(0) and no type name)
  static bool IsFlag(const CLI::Option* opt) {
    return opt->get_expected_max() == 0 || opt->get_type_name().empty();
  }

  static std::string Placeholder(const CLI::Option* opt) {
    std::string name = opt->get_lnames().empty() ? opt->get_single_name() : opt->get_lnames()[0];
    for (char& c : name) {
      c = c == '-' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    return name;
  }
};

}  // namespace

std::shared_ptr<CLI::Formatter> MakeHelpFormatter() { return std::make_shared<HelpFormatter>(); }

}  // namespace fetchscope::cli
