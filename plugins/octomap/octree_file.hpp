#pragma once

#include <memory>
#include <string>

#include <octomap/OcTree.h>

namespace dynamap::plugin {

/// The OcTree that OcTree::write() wrote to `path` (map.ot: log-odds of every node), read only
/// after its bytes are checked: the header (first line, id OcTree, size, res equal to
/// `resolution_m`), then the node stream (a log-odds float and a child byte a node, finite, no
/// deeper than the tree's 16 levels, exactly `size` nodes, nothing after them). OctoMap's own
/// reader recurses as the child bytes say and reads on past the end of a truncated file.
/// Throws MappingError "<path>: <field>: <what>".
std::unique_ptr<octomap::OcTree> readOcTreeFile(const std::string& path, double resolution_m);

}  // namespace dynamap::plugin
