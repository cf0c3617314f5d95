// Tile sets from Python: a Mapper's map written as one (Mapper.write_tiles; docs/tiles.md).

#include <knnocc/io/atomic_file.hpp>
#include <knnocc/tiles/tile_grid.hpp>
#include <knnocc/tiles/tile_set.hpp>

#include "owners.hpp"

namespace knnocc::python {

template <class Key>
std::size_t write_map_tiles(const OccupancyMap<Key>& map, const IntegrationParams& integration,
                            const std::string& model, const std::string& dir, int depth) {
  const TileGrid<Key> grid(depth);
  io::StagingDir staging(dir, tiles::is_tile_set);
  tiles::TileSetIndex ix;
  ix.resolution = map.resolution();
  ix.key_bits = Key::depth;
  ix.tile_depth = depth;
  ix.params = integration;
  ix.params.occupancy = map.params();
  ix.model = model;
  ix.model_options = "Python Mapper";
  ix.tiles = tiles::write_tiles_of(map, staging.path(), grid);
  tiles::write_index(staging.path(), ix);
  staging.commit();
  return ix.tiles.size();
}

template std::size_t write_map_tiles<OcKey>(const OccupancyMap<OcKey>&, const IntegrationParams&,
                                            const std::string&, const std::string&, int);
template std::size_t write_map_tiles<WideKey>(const OccupancyMap<WideKey>&,
                                              const IntegrationParams&, const std::string&,
                                              const std::string&, int);

}  // namespace knnocc::python
