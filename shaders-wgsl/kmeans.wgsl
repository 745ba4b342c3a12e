// Algorithms 1 and 2 of the paper: GPU k-means of surface points (position, normal) with a uniform grid
// over the centroids, the distance of Eq. (7), and the final fuzzy assignment with inverse-distance
// weights (Eq. 10). One implementation for shading points and VPLs: points are read from `data` with a
// stride (in vec4s) so the G-buffer and the VPL array are both used in place. CPU twin: crates/core/src/cpu/kmeans.rs.
//
// The steps, in the order Alg. 1 and 2 run them, each in its own file:
#import kmeans/init.wgsl
#import kmeans/grid.wgsl
#import kmeans/iterate.wgsl
#import kmeans/assign.wgsl
#import kmeans/reps.wgsl
