//! A one-layer LSTM with PyTorch's gate order (input, forget, cell, output) and parameter names
//! (`weight_ih_l0`, `weight_hh_l0`, `bias_ih_l0`, `bias_hh_l0`), written for training speed in
//! an op-by-op framework: the four gates share one sigmoid, and nothing per step costs in
//! proportion to the sequence length (400 steps for BioTac).

use candle_core::{Result, Tensor, D};
use candle_nn::VarBuilder;
use pvt3_spec::names;

#[derive(Clone, Debug)]
pub struct Lstm {
    w_ih: Tensor,
    w_hh: Tensor,
    b_ih: Tensor,
    b_hh: Tensor,
    hidden: usize,
}

impl Lstm {
    pub fn new(input: usize, hidden: usize, vb: VarBuilder) -> Result<Self> {
        let init = candle_nn::init::DEFAULT_KAIMING_UNIFORM;
        let w_ih = vb.get_with_hints((4 * hidden, input), names::WEIGHT_IH, init)?;
        let w_hh = vb.get_with_hints((4 * hidden, hidden), names::WEIGHT_HH, init)?;
        let b_ih = vb.get_with_hints(4 * hidden, names::BIAS_IH, init)?;
        let b_hh = vb.get_with_hints(4 * hidden, names::BIAS_HH, init)?;
        Ok(Self { w_ih, w_hh, b_ih, b_hh, hidden })
    }

    /// Runs `steps` steps from the hidden state `state` (`[batch, hidden]`) and a zero cell;
    /// `input(t)` is step t's projected input, `[batch, 4 · hidden]`. Returns every step's
    /// hidden state.
    fn run(&self, mut state: Tensor, steps: usize, input: impl Fn(usize) -> Result<Tensor>) -> Result<Vec<Tensor>> {
        let h = self.hidden;
        let w_hh = self.w_hh.t()?;
        let mut cell = state.zeros_like()?;
        let mut out = Vec::with_capacity(steps);
        for t in 0..steps {
            let gates = (input(t)? + state.matmul(&w_hh)?)?;
            let sig = candle_nn::ops::sigmoid(&gates)?;
            let candidate = gates.narrow(D::Minus1, 2 * h, h)?.tanh()?;
            let forget = sig.narrow(D::Minus1, h, h)?;
            let keep = sig.narrow(D::Minus1, 0, h)?;
            cell = ((forget * &cell)? + (keep * candidate)?)?;
            state = (sig.narrow(D::Minus1, 3 * h, h)? * cell.tanh()?)?;
            out.push(state.clone());
        }
        Ok(out)
    }

    /// `x`: `[batch, steps, input]` → the last hidden state, `[batch, hidden]`.
    pub fn last_hidden(&self, x: &Tensor) -> Result<Tensor> {
        let (b, t, _) = x.dims3()?;
        let (w_ih, bias) = (self.w_ih.t()?, (&self.b_ih + &self.b_hh)?);
        // Step by step, not one product over all steps narrowed per step: the gradient of each
        // narrow is a zero-padded copy of the whole sequence, quadratic in the step count.
        let states = self.run(self.zero_state(b)?, t, |k| x.narrow(1, k, 1)?.squeeze(1)?.matmul(&w_ih)?.broadcast_add(&bias))?;
        Ok(states.last().expect("at least one step").clone())
    }

    /// The same input `z` (`[batch, input]`) at each of `steps` steps → every hidden state,
    /// `[batch, steps, hidden]` (the decoder of an autoencoder).
    pub fn repeat_input(&self, z: &Tensor, steps: usize) -> Result<Tensor> {
        let projected = z.matmul(&self.w_ih.t()?)?.broadcast_add(&(&self.b_ih + &self.b_hh)?)?;
        let states = self.run(self.zero_state(z.dim(0)?)?, steps, |_| Ok(projected.clone()))?;
        Tensor::stack(&states, 1)
    }

    /// Zeros at each of `steps` steps from the hidden state `h0` (`[batch, hidden]`) and a zero
    /// cell → every hidden state, `[batch, steps, hidden]` (the decoder of Gao et al.'s RAEC).
    pub fn from_state(&self, h0: &Tensor, steps: usize) -> Result<Tensor> {
        // A zero input projects to the biases alone.
        let bias = (&self.b_ih + &self.b_hh)?.unsqueeze(0)?.broadcast_as((h0.dim(0)?, 4 * self.hidden))?;
        let states = self.run(h0.clone(), steps, |_| Ok(bias.clone()))?;
        Tensor::stack(&states, 1)
    }

    fn zero_state(&self, batch: usize) -> Result<Tensor> {
        Tensor::zeros((batch, self.hidden), self.w_hh.dtype(), self.w_hh.device())
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{DType, Device, Tensor};
    use candle_nn::{VarBuilder, VarMap};

    /// One step by hand: i, f, g, o gates of `W x + b` (PyTorch's order) from the zero state.
    #[test]
    fn one_step_matches_the_lstm_equations() {
        let varmap = VarMap::new();
        let lstm = super::Lstm::new(2, 1, VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu)).unwrap();
        let set = |name: &str, v: Tensor| varmap.data().lock().unwrap()[name].set(&v).unwrap();
        set("weight_ih_l0", Tensor::new(&[[0.5f32, -1.0], [1.0, 0.25], [2.0, 0.0], [-0.5, 1.5]], &Device::Cpu).unwrap());
        set("bias_ih_l0", Tensor::new(&[0.1f32, 0.2, 0.3, 0.4], &Device::Cpu).unwrap());
        set("bias_hh_l0", Tensor::new(&[0.0f32, 0.0, 0.0, 0.1], &Device::Cpu).unwrap());
        let x = Tensor::new(&[[[1.0f32, 2.0]]], &Device::Cpu).unwrap();
        let got = lstm.last_hidden(&x).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap()[0];
        let sig = |v: f32| 1.0 / (1.0 + (-v).exp());
        let (i, g, o) = (sig(0.5 - 2.0 + 0.1), (2.0f32 + 0.3).tanh(), sig(-0.5 + 3.0 + 0.5));
        let want = o * (i * g).tanh();
        assert!((got - want).abs() < 1e-6, "{got} vs {want}");
    }

    /// The published decoder's first step by hand: zero input, so the gates are the biases plus
    /// `W_hh h0`; the cell starts at zero.
    #[test]
    fn from_state_starts_from_the_given_hidden_state_on_zero_input() {
        let varmap = VarMap::new();
        let lstm = super::Lstm::new(1, 1, VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu)).unwrap();
        let set = |name: &str, v: Tensor| varmap.data().lock().unwrap()[name].set(&v).unwrap();
        set("weight_ih_l0", Tensor::new(&[[9.0f32], [9.0], [9.0], [9.0]], &Device::Cpu).unwrap());
        set("weight_hh_l0", Tensor::new(&[[0.5f32], [-1.0], [2.0], [1.5]], &Device::Cpu).unwrap());
        set("bias_ih_l0", Tensor::new(&[0.1f32, 0.2, 0.3, 0.4], &Device::Cpu).unwrap());
        set("bias_hh_l0", Tensor::new(&[0.0f32, 0.0, 0.0, 0.1], &Device::Cpu).unwrap());
        let h0 = Tensor::new(&[[0.8f32], [-0.4]], &Device::Cpu).unwrap();
        let states = lstm.from_state(&h0, 3).unwrap();
        assert_eq!(states.dims(), &[2, 3, 1]);
        let first = states.narrow(1, 0, 1).unwrap().flatten_all().unwrap().to_vec1::<f32>().unwrap();
        let sig = |v: f32| 1.0 / (1.0 + (-v).exp());
        for (got, h) in first.into_iter().zip([0.8f32, -0.4]) {
            let (i, g, o) = (sig(0.1 + 0.5 * h), (0.3 + 2.0 * h).tanh(), sig(0.5 + 1.5 * h));
            let want = o * (i * g).tanh();
            assert!((got - want).abs() < 1e-6, "{got} vs {want}");
        }
    }
}
