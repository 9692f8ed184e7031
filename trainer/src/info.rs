//! `pvt3 info`: what a configuration costs: input and token shapes, trainable parameters,
//! multiply-adds per sample, and every tensor's name and shape.

use std::fmt::Write;

use pvt3_models::{Config, Model, Network};

use crate::Result;

pub fn report(cfg: &Config) -> Result<String> {
    cfg.validate()?;
    let (_, varmap) = Model::init(cfg, 0)?;
    let vars = varmap.data().lock().expect("varmap lock poisoned").clone();
    let mut names: Vec<&String> = vars.keys().collect();
    names.sort();
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "input         [batch, {}]", cfg.sample_shape().iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", "));
    let _ = writeln!(w, "model         {}", cfg.architecture());
    let _ = match &cfg.network {
        Network::Pvt3(_) => writeln!(
            w,
            "tokens        {} temporal × {} spatial (+1 CLS each), patch dim {}\nparameters    {} trainable + {} frame-mask entries",
            cfg.time_tokens(),
            cfg.num_patches(),
            cfg.patch_dim(),
            cfg.parameter_count(),
            cfg.time_tokens()
        ),
        Network::Vit(_) => {
            let (h, w2) = cfg.tiled_size();
            writeln!(
                w,
                "tokens        {} patches (+1 CLS) of the {h} × {w2} tiled frame, patch dim {}\nparameters    {} trainable",
                cfg.num_patches(),
                cfg.patch_dim(),
                cfg.parameter_count()
            )
        }
        Network::Raec(r) => writeln!(
            w,
            "sequence      {} steps of {} values, LSTM hidden {}, latent {}\nparameters    {} trainable",
            cfg.time_tokens(),
            r.rnn_input(cfg),
            r.rnn_hidden,
            r.latent,
            cfg.parameter_count()
        ),
    };
    let _ = writeln!(w, "mult-adds     {} per sample", cfg.mult_adds());
    let _ = writeln!(w, "classes       {}", cfg.classes);
    let _ = writeln!(w, "\n{:<44} {:>16} {:>8}", "tensor", "shape", "values");
    for name in names {
        let v = &vars[name];
        let _ = writeln!(w, "{:<44} {:>16} {:>8}", name, format!("{:?}", v.dims()), v.elem_count());
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    #[test]
    fn icub20_report_names_the_counts() {
        let r = super::report(&pvt3_models::Config::icub20()).unwrap();
        assert!(r.contains("parameters    64272 trainable + 75 frame-mask entries"), "{r}");
        assert!(r.contains("space.layers.3.attn.qkv.weight"), "{r}");
    }

    #[test]
    fn baselines_report_their_own_shapes() {
        let r = super::report(&pvt3_models::Config::preset("vit-icub20").unwrap()).unwrap();
        assert!(r.contains("150 patches (+1 CLS) of the 30 × 150 tiled frame"), "{r}");
        let r = super::report(&pvt3_models::Config::preset("raec-biotac20").unwrap()).unwrap();
        assert!(r.contains("40 steps of 190 values, LSTM hidden 90, latent 40"), "{r}");
    }
}
