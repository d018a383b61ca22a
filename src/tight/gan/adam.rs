//! Adam (Kingma & Ba 2015) over a flat parameter slice.

/// Adam state. `β1 = 0.5` (Radford et al. 2016, DCGAN): a short momentum
/// memory suits the non-stationary adversarial objective; `β2 = 0.999`.
#[derive(Clone, Debug)]
pub(crate) struct Adam {
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
    lr: f64,
    b1: f64,
    b2: f64,
}

impl Adam {
    pub fn new(n: usize, lr: f64, b1: f64) -> Self {
        Adam { m: vec![0.0; n], v: vec![0.0; n], t: 0, lr, b1, b2: 0.999 }
    }

    /// Re-sizes and zeroes the state for reuse (no allocation once sized).
    pub fn reset(&mut self, n: usize, lr: f64, b1: f64) {
        self.m.clear();
        self.m.resize(n, 0.0);
        self.v.clear();
        self.v.resize(n, 0.0);
        self.t = 0;
        self.lr = lr;
        self.b1 = b1;
    }

    /// One descent step `p ← p − lr·m̂/(√v̂ + ε)`; `p` and `g` have length `n`.
    pub fn step(&mut self, p: &mut [f64], g: &[f64]) {
        self.t = self.t.saturating_add(1);
        let c1 = 1.0 - libm::pow(self.b1, self.t as f64);
        let c2 = 1.0 - libm::pow(self.b2, self.t as f64);
        let (b1, b2, lr) = (self.b1, self.b2, self.lr);
        for (((pi, gi), mi), vi) in p.iter_mut().zip(g).zip(&mut self.m).zip(&mut self.v) {
            *mi = b1 * *mi + (1.0 - b1) * gi;
            *vi = b2 * *vi + (1.0 - b2) * gi * gi;
            *pi -= lr * (*mi / c1) / (libm::sqrt(*vi / c2) + 1e-8);
        }
    }
}
