!> The stability test of Newton-Krylov statics: the lowest real part among the eigenvalues
!> of P^-1 K_T by Arnoldi (ARPACK dnaupd in regular mode, which = 'SR'), each step one
!> product with K_T (two evaluations) and one solve with P; a small problem directly.
submodule (dynamics_static_krylov) dynamics_static_krylov_stability
  use core_linalg, only: gen_eig_values
  use core_arpack, only: dnaupd, dneupd
  implicit none

  !> mu = eigenvalue of P^-1 K_T is a ratio to the structural stiffness (1 where the loads add
  !> nothing, 0 at a critical load). Above -STABLE_MARGIN counts as stable: the products'
  !> difference error is about 1e-8 relative (central differences with step 6e-6 of the
  !> model size against a kinematic tolerance of 1e-11), and a neutral mode (no stiffness at
  !> all: mu = 0 up to that error) counts as stable, as in the dense test.
  real(wp), parameter :: STABLE_MARGIN = 1.0e-6_wp
  !> Below this size the n x n matrix P^-1 K_T is formed by n products and solved by LAPACK.
  integer, parameter :: ARNOLDI_ABOVE = 30
  !> Up to this size an Arnoldi iteration that has taken n products gives way to the formed
  !> matrix (n more products, O(n^3) work, about 0.1 s at 400): where the lowest eigenvalues
  !> sit in a cluster (a tensioned arch: P^-1 K_T has nearly all its eigenvalues just above
  !> 1) 'SR' converged only after up to 4,500 products at 45 coordinates.
  integer, parameter :: FORM_UP_TO = 400

contains

  module procedure kry_stable
    real(wp), allocatable :: mu_r(:), mu_i(:)
    stable = .true.
    decided = size(q_dy) == 0
    if (decided) return
    call this%precondition(dyn, t, q_dy, err)
    if (.not. err%ok()) return
    if (size(q_dy) <= ARNOLDI_ABOVE) then
      call all_eigenvalues(this, dyn, t, q_dy, mu_r, mu_i, err)
      decided = err%ok()
    else
      call lowest_eigenvalues(this, dyn, t, q_dy, mu_r, mu_i, decided, err)
      if (err%ok() .and. .not. decided .and. size(q_dy) <= FORM_UP_TO) then
        call all_eigenvalues(this, dyn, t, q_dy, mu_r, mu_i, err)
        decided = err%ok()
      end if
    end if
    if (.not. (err%ok() .and. decided)) return
    stable = all(mu_r > -STABLE_MARGIN .or. abs(mu_i) > STABLE_MARGIN)
  end procedure kry_stable

  !> y = P^-1 K_T x: as x + P^-1 K_L x where P = K0 holds the dynamic modes' stiffness alone
  !> (no elastic modes, no shift: kry_load_product says why), else directly.
  subroutine apply_op(kry, dyn, t, q_dy, x, y, err)
    type(krylov_statics_t), intent(inout) :: kry
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:), x(:)
    real(wp), intent(out) :: y(:)
    type(error_t), intent(out) :: err
    real(wp) :: kv(size(x))
    if (dyn%model%n_elastic == 0 .and. kry%shift == 0) then
      call kry%load_product(dyn, t, q_dy, x, kv, err)
      if (.not. err%ok()) return
      call kry%apply_p(dyn, kv, y)
      y = x + y
    else
      call kry%product(dyn, t, q_dy, x, kv, err)
      if (.not. err%ok()) return
      call kry%apply_p(dyn, kv, y)
    end if
  end subroutine apply_op

  subroutine all_eigenvalues(kry, dyn, t, q_dy, mu_r, mu_i, err)
    type(krylov_statics_t), intent(inout) :: kry
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    real(wp), allocatable, intent(out) :: mu_r(:), mu_i(:)
    type(error_t), intent(out) :: err
    real(wp) :: a(size(q_dy), size(q_dy)), id(size(q_dy), size(q_dy)), e(size(q_dy))
    integer :: j, info
    id = 0.0_wp
    do j = 1, size(q_dy)
      id(j, j) = 1.0_wp
      e = id(:, j)
      call apply_op(kry, dyn, t, q_dy, e, a(:, j), err)
      if (.not. err%ok()) return
    end do
    allocate(mu_r(size(q_dy)), mu_i(size(q_dy)))
    call gen_eig_values(a, id, mu_r, mu_i, info)
    if (info /= 0) call err%set(ERR_NUMERIC, 'static stability (krylov): the eigenvalue ' // &
      'problem failed')
  end subroutine all_eigenvalues

  !> The three eigenvalues of smallest real part by Arnoldi, 20 vectors, relative accuracy
  !> 1e-8 (below STABLE_MARGIN on the O(1) spectrum). Not `found` when ARPACK does not
  !> converge in 300 restarts, or, up to FORM_UP_TO coordinates, in n products (the caller then
  !> decides by the formed matrix or the dense tangent).
  subroutine lowest_eigenvalues(kry, dyn, t, q_dy, mu_r, mu_i, found, err)
    type(krylov_statics_t), intent(inout) :: kry
    type(dynamics_t), intent(inout) :: dyn
    real(wp), intent(in) :: t, q_dy(:)
    real(wp), allocatable, intent(out) :: mu_r(:), mu_i(:)
    logical, intent(out) :: found
    type(error_t), intent(out) :: err
    integer, parameter :: NEV = 3, NCV = 20
    integer :: n, ido, info, iparam(11), ipntr(14), lworkl, n_products
    real(wp) :: tol, resid(size(q_dy)), v(size(q_dy), NCV), workd(3 * size(q_dy))
    real(wp) :: dr(NEV + 1), di(NEV + 1), z(1, 1), workev(3 * NCV)
    real(wp), allocatable :: workl(:)
    logical :: sel(NCV)
    character(len=240) :: msg
    found = .false.
    n = size(q_dy)
    lworkl = 3 * NCV**2 + 6 * NCV
    allocate(workl(lworkl))
    tol = 1.0e-8_wp
    ido = 0
    info = 0
    iparam = 0
    iparam(1) = 1
    iparam(3) = 300
    iparam(7) = 1
    n_products = 0
    do
      call dnaupd(ido, 'I', n, 'SR', NEV, tol, resid, NCV, v, n, iparam, ipntr, workd, &
        workl, lworkl, info)
      if (ido /= 1 .and. ido /= -1) exit
      ! ARPACK keeps its state between calls (SAVE): leaving here is safe, the next search
      ! starts with ido = 0.
      if (n_products >= n .and. n <= FORM_UP_TO) return
      n_products = n_products + 1
      call apply_op(kry, dyn, t, q_dy, workd(ipntr(1):ipntr(1) + n - 1), &
        workd(ipntr(2):ipntr(2) + n - 1), err)
      if (.not. err%ok()) return
    end do
    if (info == 1) return
    if (info < 0 .or. info > 1) then
      write(msg, '(a,i0,a)') 'static stability (krylov): ARPACK dnaupd failed (info ', info, &
        '); try &static solver = ''dense'''
      call err%set(ERR_NUMERIC, trim(msg))
      return
    end if
    call dneupd(.false., 'A', sel, dr, di, z, 1, 0.0_wp, 0.0_wp, workev, 'I', n, 'SR', NEV, &
      tol, resid, NCV, v, n, iparam, ipntr, workd, workl, lworkl, info)
    ! Fewer converged Ritz values than asked for (-14): not decided here.
    if (info /= 0 .or. iparam(5) < NEV) return
    mu_r = dr(1:iparam(5))
    mu_i = di(1:iparam(5))
    found = .true.
  end subroutine lowest_eigenvalues
end submodule dynamics_static_krylov_stability
