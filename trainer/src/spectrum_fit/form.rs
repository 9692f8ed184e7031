//! Which features a head over an image's space reads, chosen on the validation fold: the
//! texture's (levels, rings and histograms: a material's imprint wherever it lies, PhysiCLeAR's
//! objects), the pixels' (where the gel is pressed: a shape's or a still material's imprint,
//! which rings and histograms discard), or both, their logits summed. The texture's map is the
//! logistic regression's; the pixels' a ridge's scores times a scale that sets how sure they are.
//! The form whose validation windows read best wins: the texture's among equals (so that where
//! validation reads every touch either way, as it can on a small or easy set, the head keeps the
//! map it had before it read pixels), then the lower cross-entropy. A final model takes what its
//! cross-validation's runs chose (`crate::final_model`).

use ndarray::Array2;
use serde::{Deserialize, Serialize};

use super::ridge::Ridge;

/// The ridge's strengths (times the rows' count), weakest first.
pub const STRENGTHS: [f64; 6] = [1e-2, 1e-1, 1.0, 10.0, 1e2, 1e3];

/// The scales of the ridge's scores (of order one: targets of ±1) as logits.
const SCALES: [f64; 4] = [1.0, 2.0, 4.0, 8.0];

/// What a head over an image's space reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Form {
    Texture,
    Pixels,
    Both,
}

impl std::fmt::Display for Form {
    /// Its name, as `head.json` and `pvt3 cv`'s table write it.
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Form::Texture => "texture",
            Form::Pixels => "pixels",
            Form::Both => "both",
        })
    }
}

impl Form {
    pub const ALL: [Form; 3] = [Form::Texture, Form::Pixels, Form::Both];

    pub fn reads_texture(self) -> bool {
        self != Form::Pixels
    }

    pub fn reads_pixels(self) -> bool {
        self != Form::Texture
    }
}

/// A form and, where it reads the pixels, the ridge's strength and its scores' scale.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Choice {
    pub form: Form,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
}

impl Choice {
    /// The texture alone: a head without pixels, or a fit with nothing to choose by.
    pub const TEXTURE: Choice = Choice { form: Form::Texture, strength: None, scale: None };
}

/// A choice and what each form's best read on the validation windows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Chosen {
    #[serde(flatten)]
    pub choice: Choice,
    /// Each form's best validation accuracy, in [`Form::ALL`]'s order.
    pub validation: Vec<(Form, f64)>,
}

impl std::fmt::Display for Chosen {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "the camera head's form: {}", self.choice.form)?;
        if let (Some(strength), Some(scale)) = (self.choice.strength, self.choice.scale) {
            write!(f, " (ridge strength {strength}, scale {scale})")?;
        }
        let each: Vec<String> = self.validation.iter().map(|(form, a)| format!("{form} {a:.4}")).collect();
        write!(f, "; validation: {}", each.join(", "))
    }
}

/// A candidate and how it reads the validation windows.
struct Scored {
    choice: Choice,
    correct: usize,
    loss: f64,
}

/// The form that reads `labels` best from the texture's logits and each ridge's scores on the
/// validation windows (`ridges`: `(strength, scores)`), and each form's best accuracy.
pub fn choose(texture: &Array2<f64>, ridges: &[(f64, Array2<f64>)], labels: &[usize]) -> Chosen {
    let mut scored = vec![score(Choice::TEXTURE, texture.clone(), labels)];
    for (strength, scores) in ridges {
        for scale in SCALES {
            let pixels = scores * scale;
            let pick = |form| Choice { form, strength: Some(*strength), scale: Some(scale) };
            scored.push(score(pick(Form::Both), texture + &pixels, labels));
            scored.push(score(pick(Form::Pixels), pixels, labels));
        }
    }
    let n = labels.len().max(1) as f64;
    let validation = Form::ALL
        .iter()
        .map(|form| (*form, scored.iter().filter(|s| s.choice.form == *form).map(|s| s.correct).max().unwrap_or(0) as f64 / n))
        .collect();
    // The texture first among equals (the head without the pixels, whose map is the smaller);
    // then the lower loss.
    let key = |s: &Scored| (s.correct, s.choice == Choice::TEXTURE, -s.loss);
    let best = scored.into_iter().reduce(|best, s| if key(&s) > key(&best) { s } else { best });
    Chosen { choice: best.expect("the texture's candidate").choice, validation }
}

fn score(choice: Choice, logits: Array2<f64>, labels: &[usize]) -> Scored {
    let (mut correct, mut loss) = (0, 0.0);
    for (row, label) in logits.rows().into_iter().zip(labels) {
        let top = row.fold(f64::NEG_INFINITY, |m, v| m.max(*v));
        let total: f64 = row.iter().map(|v| (v - top).exp()).sum();
        loss += top + total.ln() - row[*label];
        correct += usize::from(row.iter().enumerate().all(|(j, v)| j == *label || *v < row[*label]));
    }
    Scored { choice, correct, loss: loss / labels.len().max(1) as f64 }
}

/// The head's linear map `[classes, features]` and biases for `choice`: the texture's weights in
/// the texture's columns (where it reads them), the ridge's times its scale in the pixels'.
pub fn linear_map(
    choice: Choice,
    texture: (&[f64], &[f64]),
    ridge: Option<&Ridge>,
    columns: (&[usize], &[usize]),
    features: usize,
) -> (Vec<f64>, Vec<f64>) {
    let classes = texture.1.len();
    let (mut weight, mut bias) = (vec![0.0; classes * features], vec![0.0; classes]);
    let (texture_columns, pixel_columns) = columns;
    if choice.form.reads_texture() {
        for (class, row) in texture.0.chunks(texture_columns.len().max(1)).enumerate().take(classes) {
            texture_columns.iter().zip(row).for_each(|(c, w)| weight[class * features + c] = *w);
        }
        bias.copy_from_slice(texture.1);
    }
    if let (true, Some(ridge), Some(scale)) = (choice.form.reads_pixels(), ridge, choice.scale) {
        for (class, row) in ridge.weight.rows().into_iter().enumerate() {
            pixel_columns.iter().zip(row).for_each(|(c, w)| weight[class * features + c] = scale * w);
            bias[class] += scale * ridge.bias[class];
        }
    }
    (weight, bias)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pixels that read every validation window beat a texture that reads half; a texture that
    /// reads them all keeps its form, whatever the pixels read.
    #[test]
    fn the_form_that_reads_validation_best_is_chosen() {
        let labels = [0, 1, 0, 1];
        let sure = Array2::from_shape_vec((4, 2), vec![0.05, -0.05, -0.05, 0.05, 0.05, -0.05, -0.05, 0.05]).unwrap();
        let half = Array2::from_shape_vec((4, 2), vec![1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0]).unwrap();
        let chosen = choose(&half, &[(1.0, sure.clone())], &labels);
        assert_eq!(chosen.choice.form, Form::Pixels, "{chosen}");
        assert_eq!(chosen.validation, vec![(Form::Texture, 0.5), (Form::Pixels, 1.0), (Form::Both, 0.5)]);
        let wrong = &sure * -1.0;
        assert_eq!(choose(&(&sure * 100.0), &[(1.0, wrong)], &labels).choice, Choice::TEXTURE);
        // Pixels that read as well, even surer, leave the texture's map as it was.
        assert_eq!(choose(&sure, &[(1.0, &sure * 100.0)], &labels).choice, Choice::TEXTURE);
    }
}
