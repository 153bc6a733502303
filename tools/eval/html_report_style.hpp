#pragma once

// The inline style sheet of report.html (html_report.cpp).
namespace dynamap {

inline constexpr const char* kHtmlReportCss = R"css(
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, Arial, sans-serif;
       margin: 24px auto; max-width: 1280px; padding: 0 16px; color: #222; background: #fafafa; }
h1 { margin-bottom: 2px; }
h2 { border-bottom: 1px solid #ccc; padding-bottom: 4px; margin-top: 28px; }
.sub { color: #666; margin-top: 0; font-size: 90%; }
section { margin-bottom: 12px; }
table { border-collapse: collapse; margin: 6px 18px 12px 0; background: #fff; font-size: 14px; }
caption { text-align: left; font-weight: 600; padding: 4px 0; }
th, td { border: 1px solid #ddd; padding: 4px 10px; }
th { background: #f0f0f0; text-align: left; font-weight: 600; }
td { text-align: right; font-variant-numeric: tabular-nums; }
table.counts td { text-align: center; }
.row { display: flex; flex-wrap: wrap; align-items: flex-start; gap: 12px; }
img { border: 1px solid #ccc; background: #fff; display: block; }
img.plot { max-width: 100%; width: 760px; margin-bottom: 12px; }
img.wide { max-width: 100%; width: 1000px; }
img.preview { width: 100%; }
.previews { display: grid; grid-template-columns: 1fr 1fr; gap: 12px; }
.status { padding: 2px 10px; border-radius: 10px; color: #fff; background: #777; font-weight: 600; }
.status.complete { background: #2e7d32; }
.status.interrupted { background: #ef6c00; }
.status.failed { background: #c62828; }
.error { color: #c62828; }
.barcol { width: 260px; }
.bar { height: 12px; }
.bar.p95 { background: #b0c4de; }
.bar.median { background: #36648b; }
.notes { color: #8a6d3b; font-size: 90%; }
)css";

}  // namespace dynamap
