// Replaced by the mapping module (issue 5).
namespace dynamap {
int mappingModulePlaceholder() { return 0; }
}  // namespace dynamap
