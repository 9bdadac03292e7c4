#include "tunekit/calibration/presentation/html.hpp"

#include <fmt/format.h>

namespace tunekit::calibration::html {

std::string escape(std::string_view s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string head(std::string_view title, std::string_view css, std::string_view csp) {
  std::string h = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  if (!csp.empty()) h += fmt::format("<meta http-equiv=\"Content-Security-Policy\" content=\"{}\">\n", csp);
  return h + fmt::format("<title>{}</title>\n<style>\n{}</style>\n</head>\n<body>\n", title, css);
}

std::string base_css(int max_width_px) {
  return fmt::format(
      "body{{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;margin:2em auto;max-width:{}px;color:#222}}\n"
      "h1{{font-size:1.6em}}h2{{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}}\n",
      max_width_px);
}

}  // namespace tunekit::calibration::html
