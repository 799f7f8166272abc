//! A matrix written as its rows (`serde` feature): `[[m00, m01, …], [m10, …], …]`, the layout of a
//! row-major numpy array and of the command line's JSON, where nalgebra's own `serde` writes one flat
//! list in column order. Used as `#[serde(with = "crate::matrix_rows")]` on a matrix field, and
//! `matrix_rows::option` on an `Option` of one. Vectors keep
//! nalgebra's flat list. Reading checks the shape: a wrong number of rows or columns is an error
//! naming both.

use nalgebra::SMatrix;
use serde::ser::SerializeSeq;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A matrix seen as the sequence of its rows.
struct Rows<'a, const R: usize, const C: usize>(&'a SMatrix<f64, R, C>);

/// Row `1` of matrix `0`, as a sequence of numbers.
struct Row<'a, const R: usize, const C: usize>(&'a SMatrix<f64, R, C>, usize);

impl<const R: usize, const C: usize> Serialize for Row<'_, R, C> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(Some(C))?;
        for j in 0..C {
            seq.serialize_element(&self.0[(self.1, j)])?;
        }
        seq.end()
    }
}

impl<const R: usize, const C: usize> Serialize for Rows<'_, R, C> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(Some(R))?;
        for i in 0..R {
            seq.serialize_element(&Row(self.0, i))?;
        }
        seq.end()
    }
}

/// The `R x C` matrix of `rows`, or an error naming the shape found.
fn from_rows<E: serde::de::Error, const R: usize, const C: usize>(
    rows: Vec<Vec<f64>>,
) -> Result<SMatrix<f64, R, C>, E> {
    let columns_found = rows.iter().map(Vec::len).find(|&n| n != C);
    if rows.len() != R || columns_found.is_some() {
        let found = columns_found.unwrap_or(C);
        return Err(E::custom(format!(
            "expected a {R}x{C} matrix as {R} rows of {C} numbers, got {} rows (one of {found} numbers)",
            rows.len()
        )));
    }
    Ok(SMatrix::from_fn(|i, j| rows[i][j]))
}

/// Writes `matrix` as its rows.
pub(crate) fn serialize<S: Serializer, const R: usize, const C: usize>(
    matrix: &SMatrix<f64, R, C>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    Rows(matrix).serialize(serializer)
}

/// Reads a matrix from its rows.
pub(crate) fn deserialize<'de, D: Deserializer<'de>, const R: usize, const C: usize>(
    deserializer: D,
) -> Result<SMatrix<f64, R, C>, D::Error> {
    from_rows(Vec::<Vec<f64>>::deserialize(deserializer)?)
}

/// An optional matrix as its rows, or `null`.
pub(crate) mod option {
    use super::*;

    /// Writes `matrix` as its rows, or none.
    pub(crate) fn serialize<S: Serializer, const R: usize, const C: usize>(
        matrix: &Option<SMatrix<f64, R, C>>,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        matrix.as_ref().map(Rows).serialize(serializer)
    }

    /// Reads an optional matrix from its rows.
    pub(crate) fn deserialize<'de, D: Deserializer<'de>, const R: usize, const C: usize>(
        deserializer: D,
    ) -> Result<Option<SMatrix<f64, R, C>>, D::Error> {
        Option::<Vec<Vec<f64>>>::deserialize(deserializer)?
            .map(from_rows)
            .transpose()
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix2x3, Matrix3};

    #[derive(serde::Serialize, serde::Deserialize, PartialEq, Debug)]
    struct Holder {
        #[serde(with = "super")]
        m: Matrix2x3<f64>,
        #[serde(with = "super::option")]
        o: Option<Matrix3<f64>>,
    }

    #[test]
    fn a_matrix_is_written_row_by_row_and_read_back() {
        let m = Matrix2x3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
        let holder = Holder { m, o: None };
        let json = serde_json::to_string(&holder).unwrap();
        assert_eq!(json, r#"{"m":[[1.0,2.0,3.0],[4.0,5.0,6.0]],"o":null}"#);
        assert_eq!(serde_json::from_str::<Holder>(&json).unwrap(), holder);
        let with_option = Holder {
            o: Some(Matrix3::from_fn(|i, j| (3 * i + j) as f64)),
            ..holder
        };
        let json = serde_json::to_string(&with_option).unwrap();
        assert!(
            json.contains(r#""o":[[0.0,1.0,2.0],[3.0,4.0,5.0],[6.0,7.0,8.0]]"#),
            "{json}"
        );
        assert_eq!(serde_json::from_str::<Holder>(&json).unwrap(), with_option);
    }

    #[test]
    fn a_wrong_shape_is_refused_by_name() {
        for bad in [r#"[[1.0,2.0,3.0]]"#, r#"[[1.0,2.0,3.0],[4.0,5.0]]"#, r#"[[1,2],[3,4]]"#] {
            let json = format!(r#"{{"m":{bad},"o":null}}"#);
            let error = serde_json::from_str::<Holder>(&json).unwrap_err().to_string();
            assert!(
                error.contains("expected a 2x3 matrix as 2 rows of 3 numbers"),
                "{error}"
            );
        }
    }
}
