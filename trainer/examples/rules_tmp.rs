use candle_core::D;
use pvt3_trainer::checkpoint;
use pvt3_trainer::data::Dataset;
use pvt3_trainer::evaluate::Samples;

struct P {
    top: Vec<Vec<f32>>,
    second: Vec<Vec<f32>>,
    class: Vec<Vec<u32>>,
    label: Vec<u32>,
}

fn prefixes(m: &pvt3_models::Pvt3, s: &Samples) -> P {
    let t = m.config().time_tokens();
    let mut p = P { top: vec![], second: vec![], class: vec![], label: s.labels.clone() };
    let rows: Vec<usize> = (0..s.len()).collect();
    for chunk in rows.chunks(100) {
        let (x, _) = s.batch(chunk, |_| {}).unwrap();
        let seq = m.sequence(&x, None).unwrap();
        let mut tops = vec![vec![]; chunk.len()];
        let mut secs = vec![vec![]; chunk.len()];
        let mut cls = vec![vec![]; chunk.len()];
        for k in 1..=t {
            let pr = candle_nn::ops::softmax_last_dim(&m.classify_sequence(&m.prefix(&seq, k).unwrap(), None).unwrap()).unwrap();
            let v = pr.to_vec2::<f32>().unwrap();
            let am = pr.argmax(D::Minus1).unwrap().to_vec1::<u32>().unwrap();
            for i in 0..chunk.len() {
                let mut sorted = v[i].clone();
                sorted.sort_by(|a, b| b.total_cmp(a));
                tops[i].push(sorted[0]);
                secs[i].push(sorted[1]);
                cls[i].push(am[i]);
            }
        }
        p.top.extend(tops);
        p.second.extend(secs);
        p.class.extend(cls);
    }
    p
}

// score(sample, k) -> confidence; stop at first k with score >= tau and (run consecutive same class >= need)
fn stop(p: &P, rule: usize, tau: f32) -> (f64, f64, f64) {
    let n = p.top.len();
    let t = p.top[0].len();
    let (mut right, mut used, mut full) = (0, 0, 0);
    for i in 0..n {
        let mut kk = t - 1;
        for k in 0..t {
            let score = match rule {
                0 | 1 | 2 => p.top[i][k],
                _ => p.top[i][k] - p.second[i][k],
            };
            let need = match rule {
                1 => 2,
                2 => 3,
                _ => 1,
            };
            let stable = k + 1 >= need && (0..need).all(|j| p.class[i][k - j] == p.class[i][k]);
            if score >= tau && stable {
                kk = k;
                break;
            }
        }
        right += (p.class[i][kk] == p.label[i]) as usize;
        used += kk + 1;
        full += (p.class[i][t - 1] == p.label[i]) as usize;
    }
    (right as f64 / n as f64, full as f64 / n as f64, used as f64 / (n * t) as f64)
}

fn calibrate(p: &P, rule: usize, loss: f64) -> f32 {
    let mut c: Vec<f32> = (0..p.top.len())
        .flat_map(|i| (0..p.top[0].len()).map(move |k| (i, k)))
        .map(|(i, k)| match rule {
            0 | 1 | 2 => p.top[i][k],
            _ => p.top[i][k] - p.second[i][k],
        })
        .collect();
    c.push(1.0);
    c.sort_by(|a, b| b.total_cmp(a));
    c.dedup();
    let mut chosen = 1.0;
    for tau in c {
        let (a, f, _) = stop(p, rule, tau);
        if a < f - loss - 1e-12 {
            break;
        }
        chosen = tau;
    }
    chosen
}

fn main() {
    for run in std::env::args().skip(1) {
        let (meta, model, _) = checkpoint::load(std::path::Path::new(&run)).unwrap();
        let data = Dataset::load(std::path::Path::new(&meta.provenance.data), meta.provenance.seed).unwrap();
        let split = data.split(meta.provenance.val_fold).unwrap();
        let m = model.pvt3("x").unwrap();
        let val = prefixes(m, &Samples::new(&data, &split.val, &meta.normalization));
        let test = prefixes(m, &Samples::new(&data, &split.test, &meta.normalization));
        for rule in 0..4 {
            for loss in [0.005, 0.0] {
                let tau = calibrate(&val, rule, loss);
                let (a, f, s) = stop(&test, rule, tau);
                println!("RES {run} rule{rule} loss{loss} tau {tau:.3} change {:+.2} share {:.3}", (a - f) * 100.0, s);
            }
        }
    }
}
