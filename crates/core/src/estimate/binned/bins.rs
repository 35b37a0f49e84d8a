//! The binning the three binned estimators share, as numbers: the screen tiles and the
//! cluster hierarchy's levels over the low-resolution image ([`Grid`]), the CPU estimate of
//! the list entries and walk jobs a photon needs ([`Grid::photon_bins`]), and the sizes of
//! the growable resources ([`Capacity`]). `tiled.wgsl` and `cluster.wgsl` bin with the same
//! numbers (their `TILE`, `CLUSTERS_PER_TILE`, `FANOUT`, `PHOTON_ROW` and `LIST_ROW`).

use super::Mode;

/// Tile side in low-resolution texels (`TILE` of tiled.wgsl).
pub const TILE: u32 = 8;
/// Photons per row of the photon texture (`PHOTON_ROW`), 4 texels each.
pub(super) const PHOTON_ROW: u32 = 1024;
/// List entries per row of the list texture (`LIST_ROW`).
pub(super) const LIST_ROW: u32 = 4096;
/// Nodes per row of the node texture (`NODE_ROW`), 3 texels each.
pub(super) const NODE_ROW: u32 = 1024;
/// Leaf clusters and accept lists per tile a photon's rectangle covers, on average, in the
/// first list estimate of the hierarchy modes ([`Grid::photon_bins`]). Measured: the walk
/// writes about a sixth of twice the tiles (cornell, 1280×720, 200k photons), so one per
/// tile still leaves 3× room.
pub(super) const HIERARCHY_ENTRIES_PER_TILE: u64 = 1;
/// Smallest capacity of each job list.
pub(super) const MIN_JOBS: u32 = 64;
/// Leaf clusters per tile (`CLUSTERS_PER_TILE` of cluster.wgsl).
pub(super) const CLUSTERS_PER_TILE: u32 = 8;
/// Children per side of a hierarchy node (`FANOUT`).
pub(super) const FANOUT: u32 = 4;

/// The bins over a low-resolution image: tiles of `TILE`² texels and, in the hierarchy
/// modes, `CLUSTERS_PER_TILE` leaf clusters a tile under two levels of parents, each over
/// `FANOUT`² nodes of the level below.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Grid {
    pub tiles: [u32; 2],
    /// Nodes per row and rows of hierarchy levels 1 and 2.
    pub l1: [u32; 2],
    pub l2: [u32; 2],
    /// Hierarchy nodes (tiled: one per tile).
    pub nodes: u32,
    /// Photon lists (tiled: one per tile; hierarchy: an accept list per node, then a test
    /// list per leaf).
    pub slots: u32,
}

impl Grid {
    pub fn new(low_size: [u32; 2], mode: Mode) -> Self {
        let [lw, lh] = low_size;
        let tiles = [lw.div_ceil(TILE), lh.div_ceil(TILE)];
        let l1 = [tiles[0].div_ceil(FANOUT), tiles[1].div_ceil(FANOUT)];
        let l2 = [l1[0].div_ceil(FANOUT), l1[1].div_ceil(FANOUT)];
        let n0 = tiles[0] * tiles[1];
        let (nodes, slots) = match mode {
            Mode::Tiled => (n0, n0),
            Mode::Cluster | Mode::Directional => {
                let leaves = n0 * CLUSTERS_PER_TILE;
                let nodes = leaves + l1[0] * l1[1] + l2[0] * l2[1];
                (nodes, nodes + leaves)
            }
        };
        Grid {
            tiles,
            l1,
            l2,
            nodes,
            slots,
        }
    }

    /// The first node of the leaves, of level 1 and of level 2, and the end of the nodes.
    pub fn level_first(&self) -> [u32; 4] {
        let leaves = self.tiles[0] * self.tiles[1] * CLUSTERS_PER_TILE;
        [0, leaves, leaves + self.l1[0] * self.l1[1], self.nodes]
    }

    /// Tiles and level-1 nodes under a photon whose kernel projects to `r` low-resolution
    /// texels (before the box and cone tests, so usually an overestimate; all of them when
    /// `r` is not finite): the shader's rectangle spans 2r + 2 texels, its tiles per axis ≤
    /// that / TILE + 2, its level-1 nodes per axis ≤ that / (TILE·FANOUT) + 2 (a job per
    /// photon and level-2 or level-1 node it descends into: the level-1 count bounds both
    /// job lists).
    pub fn photon_bins(&self, r: f32) -> (u64, u64) {
        let all = (self.tiles[0] * self.tiles[1]) as u64;
        let all_l1 = (self.l1[0] * self.l1[1]) as u64;
        if !r.is_finite() {
            return (all, all_l1);
        }
        let span = (2.0 * r + 2.0) / TILE as f32;
        let side = (span + 2.0).min(1e6) as u64;
        let side1 = (span / FANOUT as f32 + 2.0).min(1e6) as u64;
        ((side * side).min(all), (side1 * side1).min(all_l1))
    }

    /// List entries for photons over `tiles` tiles in all ([`Grid::photon_bins`]).
    pub fn list_entries(mode: Mode, tiles: u64) -> u64 {
        match mode {
            Mode::Tiled => tiles,
            Mode::Cluster | Mode::Directional => tiles * HIERARCHY_ENTRIES_PER_TILE,
        }
    }
}

/// Sizes of the growable resources.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Capacity {
    /// Photons the photon texture holds (a multiple of `PHOTON_ROW`).
    pub photons: u32,
    /// List entries (a multiple of `LIST_ROW`).
    pub entries: u32,
    /// Jobs of each of the cluster walk's two job lists.
    pub jobs: u32,
}

impl Capacity {
    /// The sizes before the first photons: a row of each.
    pub fn initial(mode: Mode) -> Self {
        Capacity {
            photons: PHOTON_ROW,
            entries: LIST_ROW,
            jobs: if mode == Mode::Tiled { 0 } else { MIN_JOBS },
        }
    }

    /// What `photons` photons need with `entries` list entries and `jobs` walk jobs
    /// estimated: twice their rows of photons (to a power of two, so that a slowly growing
    /// photon count does not grow the texture each frame), whole rows of entries.
    pub fn for_photons(mode: Mode, photons: u32, entries: u64, jobs: u64) -> Self {
        let rows = photons.div_ceil(PHOTON_ROW).max(1);
        let entries = entries.min(u32::MAX as u64) as u32;
        let jobs = match mode {
            Mode::Tiled => 0,
            Mode::Cluster | Mode::Directional => jobs.min(u32::MAX as u64) as u32,
        };
        Capacity {
            photons: (2 * rows).next_power_of_two() * PHOTON_ROW,
            entries: entries.div_ceil(LIST_ROW).max(1) * LIST_ROW,
            jobs: jobs.max(MIN_JOBS),
        }
    }

    /// After a frame whose lists held `entries` entries and whose job lists `jobs` jobs:
    /// room for those and a quarter more, so that a slowly changing view does not redo
    /// every frame.
    pub fn after_overflow(self, entries: u32, jobs: u32) -> Self {
        let room = |n: u32| (n as u64 + n as u64 / 4).min(u32::MAX as u64) as u32;
        Capacity {
            photons: self.photons,
            entries: room(entries).div_ceil(LIST_ROW) * LIST_ROW,
            jobs: room(jobs),
        }
    }

    /// The larger of each size (the resources never shrink).
    pub fn max(self, other: Capacity) -> Self {
        Capacity {
            photons: self.photons.max(other.photons),
            entries: self.entries.max(other.entries),
            jobs: self.jobs.max(other.jobs),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64×48 low-resolution image: 8×6 tiles; the hierarchy's 384 leaves (8 a tile), 2×2
    /// level-1 and 1×1 level-2 nodes, and a test list per leaf after the nodes' lists.
    #[test]
    fn grid_counts_tiles_nodes_and_lists() {
        let tiled = Grid::new([64, 48], Mode::Tiled);
        assert_eq!(tiled.tiles, [8, 6]);
        assert_eq!((tiled.nodes, tiled.slots), (48, 48));
        let cluster = Grid::new([64, 48], Mode::Cluster);
        assert_eq!((cluster.l1, cluster.l2), ([2, 2], [1, 1]));
        assert_eq!(cluster.nodes, 384 + 4 + 1);
        assert_eq!(cluster.slots, 389 + 384);
        assert_eq!(cluster.level_first(), [0, 384, 388, 389]);
        assert_eq!(Grid::new([64, 48], Mode::Directional), cluster);
        // Partial tiles count whole: 65×1 texels are 9×1 tiles, 3×1 level-1 nodes.
        let partial = Grid::new([65, 1], Mode::Cluster);
        assert_eq!(
            (partial.tiles, partial.l1, partial.l2),
            ([9, 1], [3, 1], [1, 1])
        );
    }

    /// A point photon (r = 0) spans 2 texels: at most 2×2 tiles; a 15-texel kernel 32
    /// texels, 4 tiles, bounded by 6×6; an unbounded one every tile; each capped by the
    /// grid.
    #[test]
    fn photon_bins_bound_the_tiles_under_a_kernel() {
        let grid = Grid::new([64, 48], Mode::Cluster);
        assert_eq!(grid.photon_bins(0.0), (4, 4));
        assert_eq!(grid.photon_bins(15.0), (36, 4));
        assert_eq!(grid.photon_bins(100.0), (48, 4));
        assert_eq!(grid.photon_bins(f32::INFINITY), (48, 4));
        assert_eq!(grid.photon_bins(f32::NAN), (48, 4));
        let big = Grid::new([1024, 1024], Mode::Cluster);
        // 128×128 tiles, 32×32 level-1 nodes: 15 texels → 6² tiles, (1 + 2)² nodes.
        assert_eq!(big.photon_bins(15.0), (36, 9));
        assert_eq!(Grid::list_entries(Mode::Tiled, 36), 36);
        assert_eq!(
            Grid::list_entries(Mode::Cluster, 36),
            36 * HIERARCHY_ENTRIES_PER_TILE
        );
    }

    /// Capacities come in whole rows: photons twice their rows to a power of two, entries
    /// rounded up to a row (at least one), jobs at least `MIN_JOBS`; after an overflow a
    /// quarter more than was written.
    #[test]
    fn capacities_round_to_rows_and_grow_with_room() {
        let c = Capacity::for_photons(Mode::Tiled, 1000, 5000, 999);
        assert_eq!((c.photons, c.entries, c.jobs), (2048, 8192, MIN_JOBS));
        let c = Capacity::for_photons(Mode::Cluster, 3 * PHOTON_ROW + 1, 0, 100);
        assert_eq!(
            (c.photons, c.entries, c.jobs),
            (8 * PHOTON_ROW, LIST_ROW, 100)
        );
        let c = Capacity::for_photons(Mode::Cluster, 0, 0, u64::MAX);
        assert_eq!(
            (c.photons, c.entries, c.jobs),
            (2 * PHOTON_ROW, LIST_ROW, u32::MAX)
        );
        let grown = Capacity::initial(Mode::Cluster).after_overflow(10_000, 100);
        assert_eq!(grown.photons, PHOTON_ROW);
        assert_eq!((grown.entries, grown.jobs), (4 * LIST_ROW, 125));
        let initial = Capacity::initial(Mode::Tiled);
        assert_eq!(
            (initial.photons, initial.entries, initial.jobs),
            (1024, 4096, 0)
        );
        assert_eq!(initial.max(grown), grown);
        assert_eq!(grown.max(initial), grown);
    }
}
