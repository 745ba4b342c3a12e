//! A frame, from the scene to the image: `pipeline` decides which passes run and records them in
//! order (the shared passes of `gi`, then the method's of `method`), `resident` keeps what outlives a
//! frame (`history`: what temporal accumulation carries to the next), `frame` is what a frame returns, and `budget` picks the clustering for a time target.

pub mod budget;
pub mod frame;
pub mod history;
pub mod pipeline;
pub mod resident;
pub mod settings;
pub mod timed;
