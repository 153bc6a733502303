// Replaced by the evaluation module (issue 2).
namespace dynamap {
int evalModulePlaceholder() { return 0; }
}  // namespace dynamap
