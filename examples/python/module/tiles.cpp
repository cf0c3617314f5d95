// Tile sets from Python: a Mapper's map written as one (Mapper.write_tiles; docs/tiles.md), the
// pieces knnocc.dask runs on a cluster (rated keyframes, one tile, the index) and merge_tiles.

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <knnocc/io/atomic_file.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/tiles/tile_grid.hpp>
#include <knnocc/tiles/tile_mapping.hpp>
#include <knnocc/tiles/tile_merge.hpp>
#include <knnocc/tiles/tile_set.hpp>

#include "binding.hpp"

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

namespace knnocc::python {

namespace {

py::dict node_out(const tiles::TileNodeInfo& n) {
  py::dict d;
  d["nodes"] = n.nodes;
  d["leaf"] = n.leaf;
  d["value"] = n.value;
  return d;
}
tiles::TileNodeInfo node_in(const py::dict& d) {
  return tiles::TileNodeInfo{d["nodes"].cast<std::uint64_t>(), d["leaf"].cast<bool>(),
                             d["value"].cast<float>()};
}

py::dict entry_out(const tiles::TileEntry& e) {
  py::dict d;
  d["coord"] = py::make_tuple(e.coord.t[0], e.coord.t[1], e.coord.t[2]);
  d["file"] = e.file;
  d["shift"] = py::make_tuple(e.shift[0], e.shift[1], e.shift[2]);
  d["keys"] = py::make_tuple(e.keys[0], e.keys[1], e.keys[2], e.keys[3], e.keys[4], e.keys[5]);
  d["occupied"] = e.occupied;
  d["free"] = e.free;
  d["bt"] = node_out(e.bt);
  d["ot"] = node_out(e.ot);
  d["bytes"] = e.bytes;
  d["sha256"] = e.sha256;
  return d;
}
std::vector<std::int64_t> integers(const py::handle& h, std::size_t n) {
  const py::tuple t = py::reinterpret_borrow<py::object>(h).cast<py::tuple>();
  if (t.size() != n) throw py::value_error("a bad tile entry");
  std::vector<std::int64_t> out;
  for (const py::handle v : t) out.push_back(v.cast<std::int64_t>());
  return out;
}

tiles::TileEntry entry_in(const py::dict& d) {
  tiles::TileEntry e;
  const auto c = integers(d["coord"], 3), s = integers(d["shift"], 3), k = integers(d["keys"], 6);
  for (std::size_t a = 0; a < 3; ++a) {
    e.coord.t[a] = c[a];
    e.shift[a] = s[a];
  }
  for (std::size_t a = 0; a < 6; ++a) e.keys[a] = k[a];
  e.file = d["file"].cast<std::string>();
  e.occupied = d["occupied"].cast<std::uint64_t>();
  e.free = d["free"].cast<std::uint64_t>();
  e.bt = node_in(d["bt"].cast<py::dict>());
  e.ot = node_in(d["ot"].cast<py::dict>());
  e.bytes = d["bytes"].cast<std::uint64_t>();
  e.sha256 = d["sha256"].cast<std::string>();
  return e;
}

template <class Key>
std::vector<TileCoord> reached(const tiles::RatedStore& store, int depth) {
  return tiles::tiles_reached(store, TileGrid<Key>(depth));
}

// One tile mapped from the rated keyframes and written; nullopt for a tile left empty.
template <class Key>
std::optional<tiles::TileEntry> map_one(const tiles::RatedStore& store, const std::string& dir,
                                        int depth, const TileCoord& c, std::size_t memory_limit,
                                        unsigned threads) {
  const TileGrid<Key> grid(depth);
  if (!grid.valid(c)) throw std::invalid_argument("tile outside the key range");
  try {
    const TileIntegrator<Key> tile = tiles::map_tile(store, grid, c, threads, memory_limit);
    if (tile.map().empty()) return std::nullopt;
    return tiles::write_tile(dir, grid, c, tile.map());
  } catch (const std::bad_alloc&) {  // MemoryLimitError, or no room for a rated keyframe
    throw io::Error((std::filesystem::path(dir) / TileGrid<Key>::file_name(c)).string(),
                    "the tile's map needs more than its memory limit of " +
                        std::to_string(memory_limit / 1000000) +
                        " MB; cut the map into smaller tiles (a deeper tile depth)");
  }
}

template <class Key>
void write_index_of(const tiles::RatedStore& store, const std::string& dir, int depth,
                    const tiles::RunDescription& run, std::vector<tiles::TileEntry> entries) {
  tiles::TileSetIndex ix = tiles::start_index<Key>(store, depth, run);
  const TileGrid<Key> grid(depth);
  std::sort(entries.begin(), entries.end(), [&](const auto& a, const auto& b) {
    return grid.morton(a.coord) < grid.morton(b.coord);
  });
  ix.tiles = std::move(entries);
  tiles::write_index(dir, ix);
}

}  // namespace

void bind_tiles(py::module_& m) {
  m.def(
      "_tiles_reached",
      [](const std::string& rated, int depth) {
        std::vector<TileCoord> coords;
        {
          const py::gil_scoped_release nogil;
          const tiles::RatedStore store = tiles::RatedStore::open(rated);
          coords = store.key_bits() == 16 ? reached<OcKey>(store, depth)
                                          : reached<WideKey>(store, depth);
        }
        py::list out;
        for (const TileCoord& c : coords) out.append(py::make_tuple(c.t[0], c.t[1], c.t[2]));
        return out;
      },
      py::arg("rated"), py::arg("depth"),
      "For knnocc.dask: the tiles the rated keyframes in `rated` reach, in the order of "
      "OctoMap's files.");
  m.def(
      "_map_tile",
      [](const std::string& rated, const std::string& dir, int depth, const py::object& coord,
         std::size_t memory_limit, unsigned threads) -> py::object {
        const std::vector<std::int64_t> xyz = integers(coord, 3);
        const TileCoord c{{xyz[0], xyz[1], xyz[2]}};
        std::optional<tiles::TileEntry> e;
        {
          const py::gil_scoped_release nogil;
          const tiles::RatedStore store = tiles::RatedStore::open(rated);
          e = store.key_bits() == 16
                  ? map_one<OcKey>(store, dir, depth, c, memory_limit, threads)
                  : map_one<WideKey>(store, dir, depth, c, memory_limit, threads);
        }
        if (!e) return py::none();
        return entry_out(*e);
      },
      py::arg("rated"), py::arg("dir"), py::arg("depth"), py::arg("coord"),
      py::arg("memory_limit") = 0, py::arg("threads") = 1,
      "For knnocc.dask: tile `coord` mapped from the rated keyframes in `rated` and written into "
      "`dir`; its index entry (a dict), or None for a tile left empty.");
  m.def(
      "_write_tile_index",
      [](const std::string& dir, const std::string& rated, int depth, const std::string& model,
         const std::string& model_options, const std::string& source, std::uint64_t first,
         std::uint64_t count, const py::list& entries) {
        std::vector<tiles::TileEntry> list;
        for (const py::handle h : entries) list.push_back(entry_in(h.cast<py::dict>()));
        const py::gil_scoped_release nogil;
        const tiles::RatedStore store = tiles::RatedStore::open(rated);
        const tiles::RunDescription run{model, model_options, source, first, count};
        if (store.key_bits() == 16)
          write_index_of<OcKey>(store, dir, depth, run, std::move(list));
        else
          write_index_of<WideKey>(store, dir, depth, run, std::move(list));
      },
      py::arg("dir"), py::arg("rated"), py::arg("depth"), py::arg("model"),
      py::arg("model_options"), py::arg("source"), py::arg("first"), py::arg("count"),
      py::arg("entries"), "For knnocc.dask: the index of a tile set from its tiles' entries.");
  m.def(
      "_sensor_reach",
      [](const std::string& sequence, std::size_t first, const py::object& count) {
        const py::gil_scoped_release nogil;
        const io::ScanSource source = io::ScanSource::open(sequence);
        std::size_t last = source.size();
        if (!count.is_none()) {
          const py::gil_scoped_acquire gil;
          last = std::min(last, first + count.cast<std::size_t>());
        }
        return io::sensor_reach(source, first, last);
      },
      py::arg("sequence"), py::arg("first") = 0, py::arg("count") = py::none(),
      "For knnocc.dask: the farthest the sensor goes from the origin along an axis (poses of a "
      "sequence folder or scan graph; 0 for a point file), as `knnocc map` decides key bits.");
  m.def(
      "merge_tiles",
      [](const py::object& dir_obj, const py::object& out_obj, std::size_t memory_limit) {
        const std::string dir = path_in(dir_obj);
        std::vector<std::string> outs;
        if (py::isinstance<py::list>(out_obj) || py::isinstance<py::tuple>(out_obj)) {
          for (const py::handle h : out_obj)
            outs.push_back(path_in(py::reinterpret_borrow<py::object>(h)));
        } else {
          outs.push_back(path_in(out_obj));
        }
        std::vector<bool> binary;
        for (const std::string& out : outs) {
          std::string e = std::filesystem::path(out).extension().string();
          for (char& ch : e) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
          if (e != ".bt" && e != ".ot")
            throw py::value_error("merge_tiles: " + out + ": the name must end in .bt or .ot");
          binary.push_back(e == ".bt");
        }
        tiles::MergeStats st;
        {
          const py::gil_scoped_release nogil;
          io::CommitGroup group;  // every file written before any is renamed into place
          for (std::size_t i = 0; i < outs.size(); ++i) {
            const tiles::MergeStats one =
                tiles::merge_tile_set(dir, outs[i], binary[i], memory_limit);
            st.tiles = one.tiles;
            st.nodes = one.nodes;
            st.bytes += one.bytes;
          }
          group.commit();
        }
        py::dict d;
        d["tiles"] = st.tiles;
        d["nodes"] = st.nodes;
        d["bytes"] = st.bytes;
        return d;
      },
      py::arg("path"), py::arg("out"), py::arg("memory_limit") = 0,
      R"(Joins the tile set in the folder `path` into one OctoMap file `out` (.bt or .ot), streamed
as `knnocc merge` does: byte for byte the one-process map's file. `out` may be a list (one .bt
and one .ot, say): all are written before any replaces a file. knnocc.Error for a damaged tile
set or one beyond OctoMap's key range, and then no file is written; {'tiles', 'nodes', 'bytes'}
(bytes of all files written).)");
}

}  // namespace knnocc::python
