//! Typed handles. Each is a dense index into one of the [`Model`](crate::Model)'s
//! tables, assigned in the order the [`ModelBuilder`](crate::ModelBuilder) received
//! the item, and valid only for the model (or its
//! [`with_inequalities`](crate::Model::with_inequalities) descendants) it came from.

use std::fmt;

macro_rules! id {
    ($(#[$doc:meta])* $name:ident, $tag:literal) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub struct $name(pub u32);

        impl $name {
            /// The dense index this handle stands for.
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($tag, "#{}"), self.0)
            }
        }
    };
}

id!(
    /// A body (moving or fixed): index into [`Model::bodies`](crate::Model::bodies).
    BodyId,
    "body"
);
id!(
    /// A constraint (one joint, finger, norm, limit pair or inequality, possibly
    /// several rows): index into [`Model::constraints`](crate::Model::constraints).
    ConstraintId,
    "constraint"
);
id!(
    /// A finger: index into [`Model::fingers`](crate::Model::fingers) and into the
    /// targets slice passed to [`Evaluation::evaluate`](crate::Evaluation::evaluate).
    FingerId,
    "finger"
);
id!(
    /// A free design variable: index into
    /// [`Layout::design_vars`](crate::Layout::design_vars).
    DesignVarId,
    "design-var"
);
