//! The light the solver propagates. Radiosity is linear in the source, so each distinct
//! tile spectrum of each emitter is one *component*: its tiles' geometric factors (gain
//! as weight) times that one spectrum. The solution per component depends on λ only
//! through the smooth reflectances and is solved on the band grid; the component's spectrum
//! stays at 1 nm. An emitter with one spectrum for every tile is one component, as before.

use crate::render::scene::Scene;

/// One spectrum of one emitter and the tiles that radiate it.
pub struct Component<'a> {
    pub emitter: usize,
    /// W·sr⁻¹·m⁻²·nm⁻¹ along the normal at gain 1, 1 nm grid.
    pub spectrum: &'a [f64],
    /// Per tile of the emitter: its gain if it radiates this spectrum, else 0.
    pub weights: Vec<f64>,
}

/// Every component of a scene, emitter by emitter.
pub struct Lights<'a> {
    pub comps: Vec<Component<'a>>,
    /// Index of each emitter's first component.
    offset: Vec<usize>,
}

impl<'a> Lights<'a> {
    pub fn new(scene: &'a Scene) -> Lights<'a> {
        let mut comps = Vec::new();
        let mut offset = Vec::new();
        for (ei, e) in scene.emitters.iter().enumerate() {
            offset.push(comps.len());
            for (k, s) in e.spectra.iter().enumerate() {
                let weights = e
                    .gains
                    .iter()
                    .zip(&e.tile_spectrum)
                    .map(|(g, t)| if *t as usize == k { *g } else { 0.0 })
                    .collect();
                comps.push(Component {
                    emitter: ei,
                    spectrum: s,
                    weights,
                });
            }
        }
        Lights { comps, offset }
    }

    /// The component tile `tile` of emitter `e` belongs to.
    pub fn of_tile(&self, scene: &Scene, e: usize, tile: usize) -> usize {
        self.offset[e] + scene.emitters[e].tile_spectrum[tile] as usize
    }

    pub fn len(&self) -> usize {
        self.comps.len()
    }

    pub fn is_empty(&self) -> bool {
        self.comps.is_empty()
    }
}
