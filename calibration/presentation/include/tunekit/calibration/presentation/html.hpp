#pragma once
// What the calibration report and the fleet report share: escaping text for HTML and the page
// head.

#include <string>
#include <string_view>

namespace tunekit::calibration::html {

/// s with &, <, > and " replaced by their character references (safe in text and in
/// double-quoted attributes).
std::string escape(std::string_view s);

/// The page's opening up to and including <body>: UTF-8, the Content-Security-Policy when csp
/// is not empty, the title, and the style sheet css.
std::string head(std::string_view title, std::string_view css, std::string_view csp = {});

/// Style rules both reports use: the body's font and width (max_width_px), the headings.
std::string base_css(int max_width_px);

/// Style rules both reports use for tables: right-aligned tabular numbers, shaded headers.
inline constexpr std::string_view kTableCss =
    "td.num{text-align:right;font-variant-numeric:tabular-nums}th{background:#f2f2f2}\n";

}  // namespace tunekit::calibration::html
