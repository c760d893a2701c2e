// The Morton grid of triangle pre-splitting (Karras & Aila 2013, §5): a cubic grid of 2^21 cells
// per axis over the scene box (cell size from its longest side, as the LBVH keys). The including
// kernel declares `scene_bounds: array<vec4<u32>>` (the scene box's words, box_words.wgsl).

#include "constants.wgsl"
#include "box_words.wgsl"
const NO_BIT: u32 = 0xffffffffu;

struct SplitGrid {
    scene_min: vec3<f32>,
    // Cells per unit and units per cell.
    scale: f32,
    cell: f32,
}

fn split_grid() -> SplitGrid {
    let b = box_of_words(scene_bounds[0], scene_bounds[1]);
    let e = b.max - b.min;
    let extent = max(e.x, max(e.y, e.z));
    if extent > 0.0 {
        return SplitGrid(b.min, MORTON_GRID / extent, extent / MORTON_GRID);
    }
    return SplitGrid(b.min, 0.0, 0.0);
}

// The first and last grid cells a box [lo, hi] overlaps on each axis. The last is the cell below
// hi when hi lies exactly on a cell boundary (a piece cut at a grid plane does not reach into the
// next cell).
struct CellRange {
    first: vec3<u32>,
    last: vec3<u32>,
}

fn cell_range(grid: SplitGrid, lo: vec3<f32>, hi: vec3<f32>) -> CellRange {
    let first = clamp(floor((lo - grid.scene_min) * grid.scale), vec3<f32>(0.0), vec3<f32>(MORTON_GRID_MAX));
    let last = max(clamp(ceil((hi - grid.scene_min) * grid.scale) - 1.0, vec3<f32>(0.0), vec3<f32>(MORTON_GRID_MAX)), first);
    return CellRange(vec3<u32>(first), vec3<u32>(last));
}

// Highest bit in which the Morton codes of two grid points differ (bit 3k+2 is x's bit k, 3k+1
// y's, 3k z's), or NO_BIT when they are in the same cell. Computed per axis: the highest
// differing coordinate bit k on axis a is Morton bit 3k + 2 - a.
fn highest_differing_bit(a: vec3<u32>, b: vec3<u32>) -> u32 {
    var best = NO_BIT;
    for (var axis = 0u; axis < 3u; axis++) {
        let x = a[axis] ^ b[axis];
        if x != 0u {
            let bit = 3u * (31u - countLeadingZeros(x)) + 2u - axis;
            if best == NO_BIT || bit > best {
                best = bit;
            }
        }
    }
    return best;
}

fn box_area(lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let e = hi - lo;
    return 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
}
