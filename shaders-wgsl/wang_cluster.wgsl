// wang_cluster: Wang et al. 2009 (seed 001) §3.2 on the GPU, the whole clustering of the shading
// points: the adaptive quadtree seeding, k-means with the Eq. (2) metric over a uniform grid of the
// centres, the centre updates and each cluster's sample point. Driven by crates/core/src/method/wang/cluster.rs;
// CPU twin: crates/core/src/method/wang/twin.rs (the same steps in the same f32 arithmetic; sums in fixed point, so exact
// and independent of the order of the atomic adds). docs/methods.md, "wang".
//
// The k-means runs on the "grid image": the pixels with x and y multiples of the step g (`step`),
// gw x gh of them (crates/core/src/method/wang/cluster.rs, grid_step); the last assignment labels every pixel.
//
// The steps, in the order they run, each in its own file (wang/common.wgsl holds what they share):
#import wang/seed.wgsl
#import wang/centres.wgsl
#import wang/grid.wgsl
#import wang/assign.wgsl
#import wang/sample.wgsl
