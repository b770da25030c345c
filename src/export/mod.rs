//! Scenes written in other programs' formats, for comparing with them:
//! [`mjcf`] (MuJoCo's XML), behind `haptloop export mjcf SCENE` and
//! `benches/peers/`.

pub mod mjcf;
